"""Benchmark: inverse kinematics for one million random reachable poses (target < 1 s), the axis
values with their velocities by the Jacobian for the same poses moving (core.machine.tables.
axis_motion: what the machine clock does for every row), forward kinematics for 100 000, on the
default machine.

Run: .venv/bin/python tests/benchmarks/bench_kinematics.py [--repeat N]
Prints the best wall time of N runs for each, and the round-trip error as a sanity check.
"""

from __future__ import annotations

import argparse
import time

# isort: off
from core.util.process import configure_process

configure_process()  # (before numpy: one BLAS thread per process, as bladecam plan)
import numpy as np  # noqa: E402
# isort: on

from core.machine.kinematics import forward_kinematics, inverse_kinematics  # noqa: E402
from core.machine.model import load_machine  # noqa: E402
from core.machine.tables import axis_motion  # noqa: E402


def random_poses(machine, side: str, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Tips in the blade box of W and axes within max_tilt_deg of the side's spindle direction."""
    rng = np.random.default_rng(seed)
    tips = np.column_stack([rng.uniform(40, 235, n), rng.uniform(-90, 90, n), rng.uniform(-60, 60, n)])
    tilt = np.radians(machine.max_tilt_deg) * np.sqrt(rng.uniform(0, 1, n))
    az = rng.uniform(-np.pi, np.pi, n)
    sign = -1.0 if side == "left" else 1.0
    axes = np.column_stack([np.sin(tilt) * np.cos(az), np.sin(tilt) * np.sin(az), sign * np.cos(tilt)])
    return tips, axes


def best_of(repeat: int, fn) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    machine = load_machine()
    tips, axes = random_poses(machine, "left", 1_000_000)
    t_ik, values = best_of(args.repeat, lambda: inverse_kinematics(machine, "left", tips, axes))
    print(f"inverse kinematics, 1 000 000 poses: {t_ik:.3f} s best of {args.repeat} (target 1 s)")
    rng = np.random.default_rng(1)
    tip_rate = rng.normal(size=tips.shape) * 0.02  # mm/ms
    axis_rate = np.cross(axes, rng.normal(size=axes.shape)) * 0.002  # 1/ms, tangent to the unit axes
    t_mo, _ = best_of(args.repeat, lambda: axis_motion(machine, "left", tips, axes, tip_rate, axis_rate))
    print(f"axis values and velocities (Jacobian), 1 000 000 poses: {t_mo:.3f} s best of {args.repeat} "
          f"({t_mo / t_ik:.2f}x the inverse kinematics alone; a central difference costs 3x)")
    n_fk = 100_000
    t_fk, (tips2, axes2) = best_of(args.repeat, lambda: forward_kinematics(machine, "left", values[:n_fk]))
    err_p = np.linalg.norm(tips2 - tips[:n_fk], axis=1).max()
    err_w = np.abs(axes2 - axes[:n_fk]).max()
    print(f"forward kinematics,    100 000 poses: {t_fk:.3f} s best of {args.repeat}; "
          f"round trip {err_p:.1e} mm, {err_w:.1e} (axis components)")


if __name__ == "__main__":
    main()
