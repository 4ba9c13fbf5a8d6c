"""Colours and names the workbench uses everywhere (one place, so views, legends and tests agree)."""

from __future__ import annotations

from core.paths.regions import REGION_CODE

#: region name -> (its code, core.paths.regions.REGION_CODE, used in the render data, colour); hues far
#: apart from each other and from the two cutters and the danger red, so that a screenshot tells them apart
REGIONS = {
    "tip": (REGION_CODE["tip"], "#3d7cff"),             # blue
    "edge": (REGION_CODE["edge"], "#ff8c1a"),           # orange
    "variable": (REGION_CODE["variable"], "#f2d31b"),   # yellow
    "internal": (REGION_CODE["internal"], "#2fc45a"),   # green
}
REGION_ORDER = ("tip", "internal", "variable", "edge")

#: the paths' single colour in the modes that do not use the regions: mode -> (legend label, colour);
#: hues apart from the regions', the cutters' and the danger red
MODE_PATHS = {
    "symmetric": ("every path symmetric (both cutters)", "#a6e22e"),   # lime
    "single": ("every path single-sided (left, then right)", "#9a6bff"),  # violet
}
LEGEND_FONT_PX = 13  # the 3D view's legend text, in pixels whatever the window's size
LEGEND_BACKGROUND = "#20242c"

LEFT_COLOUR = "#e040e8"    # magenta: the left (leading) cutter, -Z_W side
RIGHT_COLOUR = "#19d8d8"   # cyan: the right (subsequent) cutter, +Z_W side
DANGER_COLOUR = "#ff2020"  # both cutters, and violations in the plots
SAFE_COLOUR = "#2e8b57"    # the status bar's verdict on a safe plan
BLADE_FACE = "#b8c4d6"
BLADE_BACK = "#d9cfb8"
BACKGROUND = ("#262a33", "#262a33")  # plain: a gradient costs frames in a software renderer
WARNING_BG = "#ffcf66"

#: the seven steps of the schedule (core.schedule.steps): (short name for the bands, full description, colour)
STEPS = {
    1: ("1 tip, leading", "the leading (left) cutter machines the tip region", "#5b6ee1"),
    2: ("2 tip, subsequent", "the subsequent (right) cutter machines the tip region; the leading one "
        "machines the first collaborative path up to S_vl", "#7e57c2"),
    3: ("3 symmetric start", "both machine the first collaborative path symmetrically", "#26a69a"),
    4: ("4 symmetric", "symmetric machining from E_vl / E_ss to S_vs / S_sl", "#43a047"),
    5: ("5 staggered A", "the subsequent cutter slows through its variable region; the leading one "
        "finishes the path, turns and starts the next", "#ef6c00"),
    6: ("6 staggered B", "the leading cutter slows through its variable region; the subsequent one "
        "finishes the path, turns and starts the next", "#d84315"),
    7: ("7 finish", "both finish the last path and return to zero", "#78909c"),
}


def step_name(step: int) -> str:
    return STEPS.get(int(step), (f"step {step}", "", "#888888"))[0]


def hex_rgb(colour: str) -> tuple[int, int, int]:
    c = colour.lstrip("#")
    return int(c[0:2], 16), int(c[2:4], 16), int(c[4:6], 16)
