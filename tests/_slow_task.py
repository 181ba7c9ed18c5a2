"""A trial function for tests of worker processes: records its pid, then sleeps."""

import os
import time
from pathlib import Path


def sleep_and_record_pid(task: dict) -> dict:
    Path(task["pid_dir"], str(os.getpid())).touch()
    time.sleep(task["sleep_s"])
    return {"value": os.getpid()}


def misbehave(task: dict) -> dict:
    """A trial that does what its task says: hang (sleeps for an hour), exit (os._exit),
    segfault (SIGSEGV to itself), oom (a MemoryError, asking for 4 EiB); else returns its
    value. Each trial it runs leaves a file named after it in ``task["ran_dir"]``, holding
    the pid of the process that ran it."""
    import signal

    Path(task["ran_dir"], str(task["trial"])).write_text(str(os.getpid()))
    act = task.get("act", "")
    if act == "hang":
        time.sleep(3600)
    elif act == "exit":
        os._exit(3)
    elif act == "segfault":
        os.kill(os.getpid(), signal.SIGSEGV)
    elif act == "oom":
        bytearray(1 << 62)
    return {"value": task["trial"] * 10, "pid": os.getpid()}
