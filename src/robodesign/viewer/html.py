"""One self-contained HTML page from scene data (:mod:`robodesign.viewer.scene`) and plot images.

The page needs no network and no server: three.js r169 (``build/three.module.min.js`` of the npm
package ``three@0.169.0``, MIT) and its ``OrbitControls`` add-on are shipped in ``static/three/`` and
inlined as ``<script type="text/plain">`` blocks; the page's module script imports them from
``blob:`` URLs. The scene is one ``<script type="application/json" id="scene-data">`` block in which
the animation poses (float32, row-major 3×4 per node and frame) and the TCP path (float32 x, y, z)
are base64 strings (``animation.poses_b64`` with ``animation.shape`` = [frames, nodes, 12];
``paths.tcp_b64``). Plots are ``<img src="data:image/png;base64,...">``.
"""
from __future__ import annotations

import base64
import html as _html
import json
import math
from functools import lru_cache
from pathlib import Path
from typing import Dict, List, Mapping, Optional, Union

import numpy as np

from robodesign.core.spatial import matrix_to_rpy
from robodesign.viewer.meshes import b64

STATIC = Path(__file__).resolve().parent / "static"
THREE_VERSION = "0.169.0"
PLOT_CAPTIONS = {
    "q": "Joint positions q with the position limits (dashed)",
    "dq": "Joint velocities dq with ± the velocity limits (dashed)",
    "ddq": "Joint accelerations ddq with ± the acceleration limits (dashed)",
    "tau": "Drivetrain torques τ with ± the peak torques (dashed)",
    "tcp": "End-effector (TCP) path and the goal positions",
}


@lru_cache(maxsize=None)
def asset(name: str) -> str:
    text = (STATIC / name).read_text(encoding="utf-8")
    low = text.lower()
    if "</script" in low or "<!--" in low:
        raise ValueError(f"{name} cannot be inlined in a <script> element")
    return text


def _json_for_script(obj) -> str:
    # '<' only occurs inside JSON strings; \u003c keeps '</script>' and '<!--' out of the element
    return json.dumps(obj, separators=(",", ":"), ensure_ascii=False, allow_nan=False).replace("<", "\\u003c")


def page_data(scene: dict) -> dict:
    """The scene as embedded in the page: big numeric arrays become float32 base64."""
    out = dict(scene)
    anim = scene.get("animation")
    if anim:
        poses = np.asarray(anim["poses"], dtype=float)
        F = len(anim["t"])
        N = len(anim["nodes"])
        poses = poses.reshape(F, N, 12)
        a = {k: v for k, v in anim.items() if k != "poses"}
        a["poses_b64"] = b64(poses.astype("<f4"))
        a["shape"] = [F, N, 12]
        out["animation"] = a
    paths = dict(scene.get("paths") or {})
    if paths.get("tcp"):
        paths["tcp_b64"] = b64(np.asarray(paths.pop("tcp"), dtype="<f4").reshape(-1, 3))
    out["paths"] = paths
    return out


def _e(x) -> str:
    return _html.escape(str(x), quote=True)


def _fmt_pose(T) -> str:
    T = np.asarray(T, dtype=float)
    p = T[:3, 3]
    R = T[:3, :3]
    roll, pitch, yaw = matrix_to_rpy(R)
    def num(v: float, digits: int) -> str:  # rounded, and never "-0"
        return f"{round(float(v), digits) + 0.0:g}"
    return (f"xyz [{num(p[0], 4)}, {num(p[1], 4)}, {num(p[2], 4)}] m, rpy [{num(math.degrees(roll), 2)}°, "
            f"{num(math.degrees(pitch), 2)}°, {num(math.degrees(yaw), 2)}°]")


def _panel(scene: dict) -> str:
    """The side panel: layer switches, overview, the checker's verdict, goals, meshes and notes."""
    info = scene.get("info") or {}
    parts = ['<h2>Overview</h2><table>' + "".join(_overview_rows(scene, info)) + "</table>"]
    verdict = info.get("verdict")
    if verdict:
        parts.append(_verdict_html(verdict))
    goals = scene.get("goals") or []
    if goals:
        parts.append(_goals_html(goals))

    meshes = scene.get("meshes") or {}
    if meshes:
        n_tri = sum(m["n_triangles"] for m in meshes.values())
        dec = [m["name"] for m in meshes.values() if m.get("decimated")]
        txt = f"{len(meshes)} mesh files, {n_tri} triangles"
        if dec:
            txt += "; decimated: " + ", ".join(dec)
        parts.append(f"<h2>Meshes</h2><div>{_e(txt)}</div>")

    msgs = scene.get("messages") or []
    if msgs:
        parts.append("<h2>Notes</h2><ul>" + "".join(f'<li class="msg">{_e(m)}</li>' for m in msgs) + "</ul>")

    layers = [("robot", "robot", True), ("obstacle", "workcell", True), ("goal", "goals", True),
              ("tolerance", "tolerances", True), ("path", "TCP path", True), ("collision", "collision geometry", False),
              ("grid", "grid", True)]
    boxes = "".join(f'<label><input type="checkbox" data-layer="{k}"{" checked" if on else ""}> {_e(t)}</label>'
                    for k, t, on in layers)
    parts.insert(0, f'<div class="layers">{boxes}</div>')
    return "\n".join(parts)


def _overview_rows(scene: dict, info: dict) -> List[str]:
    """The overview table's rows: task, solution, robot, base, q, trajectory, cost (those the scene has)."""
    rows: List[str] = []

    def row(k, v):
        rows.append(f"<tr><th>{_e(k)}</th><td>{v}</td></tr>")

    if "task" in info:
        row("task", _e(info["task"]) + (f" ({_e(info['task_name'])})" if info.get("task_name") else ""))
    if info.get("solution"):
        row("solution", _e(info["solution"]))
    if "module_set" in info:
        row("module set", _e(info["module_set"]))
    if "modules" in info:
        row("modules", "<code>" + _e(",".join(map(str, info["modules"]))) + "</code>")
    if "dof" in info:
        row("DoF", _e(info["dof"]))
    if "base_pose" in info:
        row("base pose", _e(_fmt_pose(info["base_pose"])))
    if "base_placement" in info:
        row("base placement", _e("; ".join(info["base_placement"])))
    if "q" in info:
        row("q", "<code>" + _e(np.round(np.asarray(info["q"], float), 4).tolist()) + "</code>")
    if "duration" in info:
        anim = scene.get("animation") or {}
        row("trajectory", f"{info['duration']:.3f} s, {_e(info.get('samples', '?'))} samples, "
                          f"{len(anim.get('t', []))} frames shown (≤ {anim.get('fps', 25):g} fps + goal instants)")
    if "cost" in info and info["cost"] is not None:
        row("cost", _e(f"{info.get('cost_function', '')} = {info['cost']:.6g}"))
    return rows


def _verdict_html(verdict: dict) -> str:
    """The checker's verdict: VALID / INVALID, the cost, the first 12 violations."""
    ok = bool(verdict.get("valid"))
    v = [f'<h2>Check: <span class="{"valid" if ok else "invalid"}">{"VALID" if ok else "INVALID"}</span></h2>']
    if verdict.get("cost") is not None:
        v.append(f"<div>{_e(verdict.get('costFunction', 'cost'))} = {verdict['cost']:.6g}</div>")
    viol = verdict.get("violations") or []
    if viol:
        items = "".join(f"<li>{_e(x.get('constraint', ''))}: {_e(x.get('message', ''))}"
                        + (f" (t = {x['time']:.3f} s)" if isinstance(x.get("time"), (int, float)) else "")
                        + "</li>" for x in viol[:12])
        more = f"<li>… {len(viol) - 12} more</li>" if len(viol) > 12 else ""
        v.append(f"<ul>{items}{more}</ul>")
    return "".join(v)


def _goals_html(goals: list) -> str:
    """The goals table: ID, type, the instant it is reached (a button that shows it), tolerance and details."""
    g_rows = []
    for g in goals:
        when = "–"
        if g.get("time") is not None:
            when = f"{g['time']:.3f} s"
            if g.get("frame") is not None:
                when = f'<button class="goto" data-frame="{int(g["frame"])}" title="show this instant">{when}</button>'
        tol = "<br>".join(_e(t) for t in g.get("tolerance") or [])
        det = _e(g.get("details") or "")
        g_rows.append(f"<tr><td><b>{_e(g['id'])}</b></td><td>{_e(g['type'])}</td><td>{when}</td>"
                      f"<td>{tol}{'<br>' if tol and det else ''}{det}</td></tr>")
    return ("<h2>Goals</h2><table><tr><th>ID</th><th>type</th><th>t</th><th>tolerance</th></tr>"
            + "".join(g_rows) + "</table>")


def render_html(scene: dict, plots: Optional[Mapping[str, Union[str, bytes]]] = None,
                title: str = "robodesign viewer") -> str:
    """The page as one string. ``plots``: name → PNG (base64 text or raw bytes), shown below the view."""
    data = page_data(scene)
    fig = []
    for name, png in (plots or {}).items():
        if isinstance(png, (bytes, bytearray)):
            png = base64.b64encode(bytes(png)).decode("ascii")
        cap = PLOT_CAPTIONS.get(name, name)
        fig.append(f'<figure id="plot-{_e(name)}"><img alt="{_e(cap)}" src="data:image/png;base64,{png}">'
                   f"<figcaption>{_e(cap)}</figcaption></figure>")
    plots_html = f'<section id="plots">{"".join(fig)}</section>' if fig else ""
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="robodesign viewer (three.js {THREE_VERSION} inlined)">
<title>{_e(title)}</title>
<style>
{asset("viewer.css")}
</style>
</head>
<body>
<header><h1>{_e(title)}</h1><span id="status">loading…</span></header>
<main>
<div id="viewport"><canvas id="canvas"></canvas><div id="labels"></div>
<button id="reset-view" type="button">reset view</button>
<div id="hint">drag: rotate · right-drag: pan · wheel: zoom · space: play/pause · ←/→: step</div></div>
<aside id="panel">
{_panel(scene)}
</aside>
</main>
<div id="controls">
<button id="play" type="button" aria-pressed="false">▶ Play</button>
<input id="slider" type="range" min="0" max="0" step="1" value="0" aria-label="frame">
<span id="time"></span>
<label>speed <select id="speed"><option value="0.1">0.1×</option><option value="0.25">0.25×</option>
<option value="0.5">0.5×</option><option value="1" selected>1×</option><option value="2">2×</option></select></label>
<label><input id="loop" type="checkbox" checked> loop</label>
</div>
{plots_html}
<script type="application/json" id="scene-data">{_json_for_script(data)}</script>
<script type="text/plain" id="three-src">{asset("three/three.module.min.js")}</script>
<script type="text/plain" id="orbit-src">{asset("three/OrbitControls.js")}</script>
<script type="module">
{asset("viewer.js")}
</script>
</body>
</html>
"""


def decode_page_data(page: str) -> Dict:
    """The scene data embedded in a page (for tests and tools)."""
    start = page.index('<script type="application/json" id="scene-data">') + len(
        '<script type="application/json" id="scene-data">')
    end = page.index("</script>", start)
    return json.loads(page[start:end])
