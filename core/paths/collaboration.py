"""How collaborative a plan is: the warning the command line and the workbench both give when fewer
than half of its contour paths are machined from both sides (the paper's plans are mostly so)."""

from __future__ import annotations

from core.paths.plan import PathPlan

#: below this share of collaborative contours a plan warns
LOW_SHARE = 0.5
#: a tip path's reason (core.paths.regions) -> the parameter that would make it collaborative
REMEDY = {"staggered ratio": "raise K_max", "spacing <=": "lower h_safe", "thin middle": "lower h_safe"}


def collaboration_warning(plan: PathPlan) -> str:
    """'' when most contour paths are collaborative (or the mode does not use the regions); else a
    warning naming the share and, per reason the tip paths went single-sided, the parameter that would
    change it."""
    if plan.params.mode != "collaborative" or not plan.regions:
        return ""
    tips = [r for r in plan.regions if r.is_tip]
    n, n_collab = len(plan.regions), len(plan.regions) - len(tips)
    if n_collab >= LOW_SHARE * n:
        return ""
    p = plan.params
    now = {"raise K_max": f"raise K_max (now {p.k_max:g})",
           "lower h_safe": f"lower h_safe (now {p.h_safe:g} mm)"}
    remedies: dict[str, int] = {}
    for r in tips:
        remedy = next((v for k, v in REMEDY.items() if r.reason.startswith(k)), "raise K_max")
        remedies[remedy] = remedies.get(remedy, 0) + 1
    how = " or ".join(f"{now[k]}: {c} path{'s' if c != 1 else ''}"
                      for k, c in sorted(remedies.items(), key=lambda kv: -kv[1]))
    if n_collab == 0:
        return f"NOT COLLABORATIVE: all {n} paths single-sided (tip region); {how}"
    return f"only {n_collab} of {n} paths collaborative ({100 * n_collab / n:.0f} %); {how}"
