"""What ``bladecam verify`` reports: one line per finding, each of a kind (``KINDS``); past
``SHOWN_PER_KIND`` of a kind the rest are counted, not listed, so that the summary's counts add up to the
findings found."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: the kinds of finding, in the order the summary lists them
KINDS = ("file set", "digest", "pairs", "time column", "tip spacing", "tool clearance", "feed", "path acceleration",
         "surface", "completeness", "off path", "labels", "order", "forward kinematics", "axis range", "axis speed",
         "axis acceleration", "axis velocities", "collision")
SHOWN_PER_KIND = 5
LINE_MAX = 200


@dataclass
class Report:
    """``findings``: the lines shown, one finding each (at most SHOWN_PER_KIND of a kind, each at most
    LINE_MAX characters); ``counts``: every finding per kind, shown or not; ``figures``: what was
    measured; ``trusted``: what was taken as written (one line); ``kinds``: each shown line's kind."""

    findings: list[str] = field(default_factory=list)
    figures: dict = field(default_factory=dict)
    counts: dict[str, int] = field(default_factory=dict)
    shown: dict[str, int] = field(default_factory=dict)
    kinds: list[str] = field(default_factory=list)
    trusted: str = ""

    def bad(self, kind: str, msg: str, count: int = 1) -> None:
        """One finding of ``kind`` (``count`` > 1: the line stands for that many of them)."""
        if kind not in KINDS:
            raise ValueError(f"unknown kind of finding {kind!r}")
        self.counts[kind] = self.counts.get(kind, 0) + count
        if self.shown.get(kind, 0) < SHOWN_PER_KIND:
            self.shown[kind] = self.shown.get(kind, 0) + 1
            self.findings.append(msg if len(msg) <= LINE_MAX else msg[:LINE_MAX - 3] + "...")
            self.kinds.append(kind)

    def many(self, kind: str, index: np.ndarray, line) -> None:
        """A finding of ``kind`` at each of ``index`` (an int array), ``line(i)`` its text: the first
        lines shown, every one counted."""
        room = max(SHOWN_PER_KIND - self.shown.get(kind, 0), 0)
        for i in index[:room]:
            self.bad(kind, line(i))
        if len(index) > room:
            self.counts[kind] = self.counts.get(kind, 0) + len(index) - room

    def merge(self, other: Report) -> None:
        """Add another report's findings (a helper process's), keeping the caps per kind."""
        for kind, msg in zip(other.kinds, other.findings, strict=True):
            self.bad(kind, msg)
        for kind, n in other.counts.items():
            rest = n - other.shown.get(kind, 0)
            if rest > 0:
                self.counts[kind] = self.counts.get(kind, 0) + rest
        self.figures.update(other.figures)

    @property
    def total(self) -> int:
        return sum(self.counts.values())

    def summary(self) -> str:
        """The last line: "ok: 0 findings", or "FAIL: N findings, M shown above (kind n, kind m: s shown
        and n - s more, ...)": the kinds' counts add up to N, the shown ones to M."""
        if not self.total:
            return "ok: 0 findings"
        parts = []
        for kind in (k for k in KINDS if self.counts.get(k)):
            n, shown = self.counts[kind], self.shown.get(kind, 0)
            parts.append(f"{kind} {n}" if n == shown else f"{kind} {n}: {shown} shown and {n - shown} more")
        return f"FAIL: {self.total} findings, {len(self.findings)} shown above ({'; '.join(parts)})"

    def figure_lines(self, width: int = 150) -> list[str]:
        """The figures as short lines "figures: key value, ...", the plan's own first, then each side's
        (keys left_*, right_*), a side starting a new line."""
        groups: dict[str, list[str]] = {"plan": [], "left": [], "right": []}
        for key, value in self.figures.items():
            side = key.partition("_")[0]
            groups[side if side in ("left", "right") else "plan"].append(f"{key} {value}")
        lines = []
        for items in groups.values():
            line = ""
            for item in items:
                if line and len(line) + len(item) + 2 > width:
                    lines.append(line)
                    line = ""
                line = f"{line}, {item}" if line else f"figures: {item}"
            if line:
                lines.append(line)
        return lines
