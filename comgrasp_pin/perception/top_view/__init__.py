"""The top view: the rod on the table, seen from above, and a grasp pose at its centre.

``top_down.detect_rod_top_down`` runs the steps, each a module of its own:

- the table (``table_plane``: its plane where the camera's pose is not known;
  ``table_view``: its height, noise and the cleaned image);
- what stands on it, height first (``standing``; ``registration``: is the colour usable);
- is it one rod (``rod_shape``, ``rod_alongside``, ``rod_pieces``, ``rod_flat``, ``thin_parts``,
  ``end_heights``), refused with the reason where it is not; a thin part too low to stand
  followed to its end (``joined_part``);
- where the jaws can grasp it (``grasp_points``), reported as a ``rod_detection.RodDetection``.

The public names are ``comgrasp_pin.perception``'s.
"""
