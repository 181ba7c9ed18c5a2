"""Decisions as pure functions, no simulator: the regrasp decision, the retry policy, the
put-down geometry, the holding moment of the jaws.

Layer: imports ``estimation``, ``motion`` and the shared modules (``config``, ``geometry``,
``workcell``, ``errors``); nothing that acts or sees.
"""
