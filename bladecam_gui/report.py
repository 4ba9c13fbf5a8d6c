"""The job report: one self-contained HTML file (print it from a browser) with the blade, the tool, the
machine, every parameter, the plan's figures (verdict, times, the time per step, spacing and
clearance, how collaborative, scallop), its warnings and a picture of the 3D view. Written whole or not
at all (a temporary file beside it, then renamed). No Qt here but the picture's encoding."""

from __future__ import annotations

import base64
import html
import time
from dataclasses import fields
from pathlib import Path

import numpy as np

from core.errors import OutputError
from core.util.files import write_text_whole

from .plan_data import PlanData
from .widgets import navigation as nav
from .widgets.job_panel import COLUMNS, cycle_rows, job_summary

STYLE = ("body{font-family:sans-serif;max-width:60em;margin:1.5em auto;color:#222}"
         "table{border-collapse:collapse;margin:.4em 0 1em}td,th{border:1px solid #bbb;padding:2px 8px;"
         "text-align:left}th{background:#eee}.bad{color:#c00;font-weight:bold}.ok{color:#070;font-weight:bold}"
         "img{max-width:100%;border:1px solid #888}@media print{body{margin:0}}")


def png_bytes(image: np.ndarray) -> bytes:
    """An (h, w, 3 or 4) uint8 image as PNG bytes (through Qt's encoder)."""
    from PySide6.QtCore import QBuffer, QByteArray, QIODevice
    from PySide6.QtGui import QImage

    img = np.ascontiguousarray(image[..., :3], dtype=np.uint8)
    h, w = img.shape[:2]
    qimg = QImage(img.data, w, h, 3 * w, QImage.Format.Format_RGB888).copy()
    data = QByteArray()
    buf = QBuffer(data)
    buf.open(QIODevice.OpenModeFlag.WriteOnly)
    qimg.save(buf, "PNG")
    buf.close()
    return bytes(data)


def _table(rows, head: tuple[str, ...] | None = None) -> str:
    out = ["<table>"]
    if head:
        out.append("<tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>")
    for row in rows:
        out.append("<tr>" + "".join(f"<td>{html.escape(str(v))}</td>" for v in row) + "</tr>")
    out.append("</table>")
    return "".join(out)


def report_html(data: PlanData, picture_png: bytes | None = None) -> str:
    """The report of a shown plan (it needs its schedule)."""
    res = data.result
    plan, fig, p = res.plan, res.figures, res.plan.params
    info = data.blade.blade.info()
    e = html.escape
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>bladecam job report: "
             f"{e(info['name'])}</title><style>{STYLE}</style></head><body>",
             f"<h1>Job report: {e(info['name'])}</h1>",
             f"<p>bladecam workbench, {e(time.strftime('%Y-%m-%d %H:%M'))}</p>"]
    found = nav.violations_of(data)
    runs = found.n
    verdict = ("<span class='ok'>SAFE</span>" if found.safe else
               f"<span class='bad'>{e(found.verdict())}</span> (runs of consecutive time samples that "
               f"break the safety rule or collide): {e(found.kinds_text())}. What to change: "
               + e("; ".join(found.advice())))
    parts.append(f"<h2>Verdict</h2><p>{verdict}</p>")
    if picture_png:
        parts.append("<h2>Picture</h2><img alt='the 3D view' src='data:image/png;base64,"
                     + base64.b64encode(picture_png).decode("ascii") + "'>")
    parts.append("<h2>Blade</h2>" + _table([
        ("name", info["name"]), ("source", data.job.source), ("propeller axis", data.job.axis),
        ("tip radius", f"{info['tip_radius_mm']:g} mm"), ("hub radius", f"{info['hub_radius_mm']:g} mm"),
        *((f"chord at {k} R", "–" if v is None else f"{v:g} mm") for k, v in info["chord_mm"].items()),
        *((f"max thickness at {k} R", "–" if v is None else f"{v:g} mm")
          for k, v in info["max_thickness_mm"].items())]))
    parts.append("<h2>Tool</h2>" + _table([("ball-nose radius r", f"{p.tool_radius:g} mm"),
                                           ("stick-out d_T", f"{p.tool_length:g} mm")]))
    machine = res.machine
    if machine is not None:
        parts.append("<h2>Machines</h2><p>two mirrored XYZ-3RPS hybrid machines</p>" + _table([
            (f.name.replace("_", " "), getattr(machine, f.name)) for f in fields(machine)
            if isinstance(getattr(machine, f.name), (int, float))]))
    params = [(f.name, getattr(p, f.name)) for f in fields(p)]
    params += [("speed-stage profile", data.job.profile),
               ("CL time step", "auto (dd at the feed)" if data.job.period is None
                else f"{data.job.period:g} ms"),
               ("controllers' period used", f"{res.period:g} ms" if res.period else "–")]
    parts.append("<h2>Parameters</h2>" + _table(params, ("parameter", "value")))
    counts = plan.region_counts()
    coll = fig.get("collaboration", {}).get("paths", {})
    scallop = fig.get("scallop", {})
    parts.append("<h2>Figures</h2>" + _table([
        ("mode", fig["mode"]), ("paths", f"{counts['paths']}: {counts['tip_paths']} tip, "
                                         f"{counts['collaborative_paths']} collaborative"),
        ("collaborative share of the contours",
         f"{100 * coll['collaborative_share']:.1f} %" if "collaborative_share" in coll else "–"),
        ("total time", f"{fig['total_time_s'] / 60:.2f} min"),
        ("minimum tip spacing", f"{fig['min_tip_spacing_mm']:.3f} mm (h_safe {p.h_safe:g} mm)"),
        ("minimum tool clearance", f"{fig['min_capsule_clearance_mm']:.3f} mm"),
        ("violations", f"{runs}" + (f": {found.kinds_text()}" if runs else "")),
        ("largest scallop height", f"{scallop['max_mm']:.4f} mm (mean {scallop['mean_mm']:.4f} mm)"
         + (f"; {len(scallop['uncut_paths'])} paths leave a strip uncut" if scallop.get("uncut_paths")
            else "") if scallop else "–")]))
    if "step_time_s" in fig:
        parts.append("<h2>Cycle time per step</h2>" + _table(cycle_rows(fig), COLUMNS))
        summary = job_summary(fig)
        if summary:
            parts.append(f"<p>{e(summary)}</p>")
    warnings = list(dict.fromkeys([*p.warnings(), *plan.warnings]))  # (the paths repeat the parameters')
    parts.append("<h2>Warnings</h2>" + ("<ul>" + "".join(f"<li>{e(w)}</li>" for w in warnings) + "</ul>"
                                        if warnings else "<p>none</p>"))
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(path: str | Path, text: str) -> Path:
    """Write the report whole or not at all (a temporary file beside it, renamed into place);
    OutputError naming the file on failure."""
    return write_text_whole(path, text, "the report")


class ReportAction:
    """File > Save job report: the report of the plan shown, with a picture of the 3D view as it is."""

    def __init__(self, window):
        self.parent_widget = window
        self.window = window

    def dialog(self) -> None:
        from PySide6.QtWidgets import QFileDialog

        from .settings import settings

        folder = str(settings().value("dirs/reports", ""))
        path, _ = QFileDialog.getSaveFileName(self.parent_widget, "Save the job report", folder,
                                              "HTML report (*.html)")
        if path:
            if not path.lower().endswith((".html", ".htm")):
                path += ".html"
            settings().setValue("dirs/reports", str(Path(path).parent))
            self.save(path)

    def save(self, path: str | Path) -> Path | None:
        """Write the report to ``path`` (a dialog says why not, when it cannot)."""
        from .guard import show_error

        data = self.window.state.plan
        try:
            if data is None or not data.has_schedule:
                raise OutputError("there is no plan to report yet: wait until the plan is shown")
            text = report_html(data, png_bytes(self.window.viewport.screenshot()))
            out = write_report(path, text)
        except Exception as exc:  # a dialog, never a traceback
            show_error(self.parent_widget, "Cannot save the report", exc)
            return None
        self.window.statusBar().showMessage(f"report written to {out}", 15000)
        return out
