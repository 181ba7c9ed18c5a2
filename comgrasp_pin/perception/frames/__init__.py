"""Frames in: what a camera gives, made into what the views measure in.

- ``camera_model``: a real camera's intrinsics as its driver gives them; undistortion.
- ``camera_input``: a depth in metres and a colour image checked and undistorted.
- ``rgbd_files``: a frame saved as files (depth PNG/TIFF/.npy, colour, camera info).
- ``rgbd_bag``: a frame as a ROS 2 or ROS 1 bag records it (REP 118; ``bag_topics``:
  which topic is which); ``static_tf``: the camera's pose from the bag's ``/tf_static``.
- ``depth_frames``: a still camera's depth frames averaged in time.

The public names are ``comgrasp_pin.perception``'s.
"""
