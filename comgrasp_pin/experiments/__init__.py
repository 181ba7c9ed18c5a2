"""The paper's experiments, run at scale: trials, results files, figures and reports.

Trials and their design (the tilt calibration), the resumable runner (local worker
processes or Ray tasks), run files, sweeps over config values, statistics, the report
(``report/``: figures and tables, which reads rows and never runs trials).

Layer: under ``cli`` only; imports ``simulation`` and everything under it.
"""
