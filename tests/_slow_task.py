"""A trial function for tests of worker processes: records its pid, then sleeps."""

import os
import time
from pathlib import Path


def sleep_and_record_pid(task: dict) -> dict:
    Path(task["pid_dir"], str(os.getpid())).touch()
    time.sleep(task["sleep_s"])
    return {"value": os.getpid()}
