"""The paper's experiments, run at scale: trials, results files, figures and reports."""
