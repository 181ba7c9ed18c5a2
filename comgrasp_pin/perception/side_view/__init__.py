"""The side view: the rod held in the jaws, from the side camera on the gripper (ee frame).

``side_view.observe_held_rod`` runs the steps, each a module of its own:

- the points that may be the held rod (``held_region``) and the depth's surface line
  (``side_depth``);
- is it one rod (``held_pieces``), and its axis (``held_axis``: ``rod_axis`` and its
  ``cylinder_fit`` for a round handle, ``flat_face`` for a flat bar);
- where it ends and where its centre lies (``rod_ends``), reported as a
  ``side_view.SideView``.

The public names are ``comgrasp_pin.perception``'s.
"""
