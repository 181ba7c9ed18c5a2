"""Scenes the project never built, for the perception benchmarks and their tests.

Fixtures, not the library: they build MuJoCo worlds apart from the workcell and judge the
perception's answers against them. ``scenes`` and ``families``: table scenes for the top view
(``benchmarks/unseen_scenes.py``, ``tests/test_unseen_scenes.py``); ``wrist`` and
``wrist_families``: held-rod scenes for the side view (``benchmarks/unseen_wrist_scenes.py``,
``tests/test_unseen_wrist_scenes.py``). Import as ``unseen`` with ``benchmarks/`` on
``sys.path`` (a script in ``benchmarks/`` has it there; the tests add it).
"""
