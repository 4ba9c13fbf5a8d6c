"""Draw the application icon: resources/bladecam.svg and resources/bladecam.png (256 x 256).

The motif: a blade section (a thin, cambered airfoil) between two ball nose cutters, one on each
side and slightly staggered, as in double-sided collaborative machining.

    .venv/bin/python packaging/make_icon.py          # rewrites both files
    .venv/bin/python packaging/make_icon.py --size 512 --out /tmp/icon.png

The SVG is written by hand from a few numbers; the PNG is that SVG rendered by Qt's SVG renderer
(offscreen, no display needed).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

RESOURCES = Path(__file__).resolve().parent.parent / "resources"

# Blade section: upper and lower cubic Bezier curves from the leading edge LE to the trailing edge TE.
LE, TE = (26.0, 150.0), (230.0, 104.0)
UPPER = (LE, (78.0, 92.0), (170.0, 84.0), TE)
LOWER = (TE, (170.0, 124.0), (84.0, 150.0), LE)
BALL = 15.0  # ball radius of both cutters (px)
TOP_X, BOTTOM_X = 104.0, 148.0  # the two cutters' axes: staggered, not opposite each other


def _bezier(p, t):
    (x0, y0), (x1, y1), (x2, y2), (x3, y3) = p
    u = 1.0 - t
    return (u**3 * x0 + 3 * u * u * t * x1 + 3 * u * t * t * x2 + t**3 * x3,
            u**3 * y0 + 3 * u * u * t * y1 + 3 * u * t * t * y2 + t**3 * y3)


def _surface_y(curve, x: float) -> float:
    """y of a Bezier curve at abscissa x (bisection on t; x is monotone along both curves)."""
    lo, hi = 0.0, 1.0
    increasing = curve[3][0] > curve[0][0]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (_bezier(curve, mid)[0] < x) == increasing:
            lo = mid
        else:
            hi = mid
    return _bezier(curve, 0.5 * (lo + hi))[1]


def _cutter(x: float, tip_y: float, direction: int) -> str:
    """A ball nose cutter on the vertical line x whose ball touches the surface at tip_y.

    direction -1: comes from above (shank above the ball); +1: from below.
    """
    r = BALL
    cy = tip_y + direction * r  # ball centre
    shank_end = 6.0 if direction < 0 else 250.0
    y0, y1 = sorted((cy, shank_end))
    collar_y = cy - 62.0 if direction < 0 else cy + 50.0
    flutes = "".join(
        f'<line x1="{x - r + 1:.1f}" y1="{cy + direction * k:.1f}" x2="{x + r - 1:.1f}" '
        f'y2="{cy + direction * (k + 12):.1f}" stroke="#a35410" stroke-width="3"/>'
        for k in (12.0, 26.0, 40.0))
    return (f'<rect x="{x - r:.1f}" y="{y0:.1f}" width="{2 * r:.1f}" height="{y1 - y0:.1f}" '
            f'fill="url(#shank)"/>'
            f'<rect x="{x - r:.1f}" y="{min(cy, cy + direction * 50):.1f}" width="{2 * r:.1f}" height="50" '
            f'fill="#f28c28"/>'
            f'{flutes}'
            f'<circle cx="{x:.1f}" cy="{cy:.1f}" r="{r:.1f}" fill="#f28c28"/>'
            f'<rect x="{x - r - 3:.1f}" y="{collar_y:.1f}" width="{2 * r + 6:.1f}" height="12" rx="2" '
            f'fill="#5b6673"/>')


def svg() -> str:
    def pts(c):
        return " ".join(f"{x:.1f},{y:.1f}" for x, y in c[1:])

    blade = f"M {LE[0]:.1f},{LE[1]:.1f} C {pts(UPPER)} C {pts(LOWER)} Z"
    top_tip = _surface_y(UPPER, TOP_X)
    bottom_tip = _surface_y(LOWER, BOTTOM_X)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<!-- bladecam icon, drawn by packaging/make_icon.py -->
<svg xmlns="http://www.w3.org/2000/svg" width="256" height="256" viewBox="0 0 256 256">
  <defs>
    <linearGradient id="bg" x1="0" y1="0" x2="0" y2="1">
      <stop offset="0" stop-color="#274b74"/><stop offset="1" stop-color="#12263f"/>
    </linearGradient>
    <linearGradient id="blade" x1="0" y1="0" x2="0" y2="1">
      <stop offset="0" stop-color="#f2f6fa"/><stop offset="1" stop-color="#93a3b5"/>
    </linearGradient>
    <linearGradient id="shank" x1="0" y1="0" x2="1" y2="0">
      <stop offset="0" stop-color="#8c98a6"/><stop offset="0.45" stop-color="#e6ebf0"/>
      <stop offset="1" stop-color="#7a8694"/>
    </linearGradient>
  </defs>
  <rect x="4" y="4" width="248" height="248" rx="44" fill="url(#bg)"/>
  <path d="{blade}" fill="url(#blade)" stroke="#0b1726" stroke-width="3" stroke-linejoin="round"/>
  {_cutter(TOP_X, top_tip, -1)}
  {_cutter(BOTTOM_X, bottom_tip, +1)}
</svg>
"""


def render_png(svg_text: str, size: int, out: Path) -> None:
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtCore import QByteArray, Qt
    from PySide6.QtGui import QGuiApplication, QImage, QPainter
    from PySide6.QtSvg import QSvgRenderer

    _app = QGuiApplication.instance() or QGuiApplication([sys.argv[0]])  # noqa: F841 (kept alive)
    renderer = QSvgRenderer(QByteArray(svg_text.encode()))
    if not renderer.isValid():
        raise SystemExit("make_icon: Qt could not parse the generated SVG")
    image = QImage(size, size, QImage.Format.Format_ARGB32_Premultiplied)
    image.fill(Qt.GlobalColor.transparent)
    painter = QPainter(image)
    painter.setRenderHint(QPainter.RenderHint.Antialiasing)
    renderer.render(painter)
    painter.end()
    if not image.save(str(out), "PNG"):
        raise SystemExit(f"make_icon: could not write {out}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256, help="PNG width and height in px (default 256)")
    ap.add_argument("--out", type=Path, default=None, help="PNG path (default resources/bladecam.png; "
                    "the SVG is then written next to resources/ too)")
    args = ap.parse_args(argv)
    text = svg()
    if args.out is None:
        (RESOURCES / "bladecam.svg").write_text(text, encoding="utf-8")
        png = RESOURCES / "bladecam.png"
    else:
        png = args.out
    render_png(text, args.size, png)
    print(f"wrote {png}" + ("" if args.out else f" and {RESOURCES / 'bladecam.svg'}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
