"""The job's time per step of the seven-step schedule (core.schedule.steps), from the time column.

The job is in a step until both cutters have left it: the job's step at a sample is the earlier of the
two cutters' steps (the subsequent cutter's tip pass is step 2 while the leading cutter, with no
collaborative path to wait for, already returns in its step 7). Each interval between two samples
counts for the job's step at its first sample, so the steps' times add up to the job's total time.
"""

from __future__ import annotations

import numpy as np

STEPS = tuple(range(1, 8))


def job_step(left_step: np.ndarray, right_step: np.ndarray) -> np.ndarray:
    """(n,) the job's step per sample: the earlier of the two cutters' steps."""
    return np.minimum(left_step, right_step)


def step_times(t_ms: np.ndarray, left_step: np.ndarray, right_step: np.ndarray) -> dict[str, float]:
    """Seconds per step '1' ... '7' (every step, 0 where the job has none of it), summing to the job's
    time t_ms[-1] - t_ms[0]."""
    step = job_step(left_step, right_step)
    dt = np.diff(np.asarray(t_ms, float)) / 1000.0
    per = np.bincount(np.asarray(step[:-1], np.int64), weights=dt, minlength=len(STEPS) + 1)
    return {str(k): round(float(per[k]), 3) for k in STEPS}
