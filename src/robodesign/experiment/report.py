"""Reports of a results folder, computed from ``evaluations.sqlite`` only (so a resumed experiment gets the
same report as an uninterrupted one).

* ``evaluations.csv`` – one row per evaluation (task, optimizer, seed, evaluation, candidate, feasible,
  stage, cost, best cost so far, wall time, evaluation time);
* ``anytime_evals.csv`` / ``anytime_time.csv`` – best cost so far vs evaluations / vs wall time:
  median, quartiles, min and max over seeds (a seed with no feasible design yet counts as +inf; a
  statistic that is +inf is left empty);
* ``plots/<task>.png`` – both curves per task, one line (median) and band (min–max) per optimizer;
* ``summary.csv`` / ``summary.md`` – per task × optimizer (see :data:`SUMMARY_COLUMNS`);
* ``best/<task>/<optimizer>-seed<k>_view.html`` – the 3-D view (robodesign view) of a best solution: every
  task's best robot always, further run bests up to :data:`VIEW_PAGES_MAX` pages in all;
* ``index.html`` – the tables, the plots and the best robots, with links to the files and the 3-D views.
  Tables scroll inside themselves, never the page, and headers wrap at ``_``: it fits a 1400 px window.
"""
from __future__ import annotations

import csv
import html
import json
import math
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from robodesign.core.errors import InputError
from robodesign.experiment.storage import ExperimentDB

SUMMARY_COLUMNS = ("task", "optimizer", "seeds", "evaluations", "best_cost_median", "best_cost_min",
                   "best_cost_max", "feasible_rate", "seeds_feasible", "evals_to_first_feasible_median",
                   "time_to_best_s_median", "eval_seconds_mean", "best_run")
TIME_POINTS = 200
VIEW_PAGES_MAX = 30  # 3-D view pages per report (each ~1 MB, three.js is embedded); task bests always get one


def _f(v, nd=6) -> str:
    """A cell: ``nd`` significant digits, or with ``nd=None`` the shortest text that reads back as the same
    float (costs in evaluations.csv equal the database's exactly)."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return ""
    if isinstance(v, float):
        return repr(v) if nd is None else f"{v:.{nd}g}"
    return str(v)


def _slug(name: str) -> str:
    return name.replace("/", "__")


def _stats(vals: Sequence[float]) -> Tuple[float, float, float, float, float]:
    a = np.asarray(vals, dtype=float)
    if a.size == 0:
        return (math.inf,) * 5
    # percentile with +inf entries: np.percentile gives nan when interpolating between inf values; sort manually
    a = np.sort(a)

    def pct(q):
        pos = (a.size - 1) * q
        lo, hi = int(math.floor(pos)), int(math.ceil(pos))
        if lo == hi or a[lo] == a[hi]:
            return float(a[lo])
        if not math.isfinite(a[hi]):
            return math.inf
        return float(a[lo] + (a[hi] - a[lo]) * (pos - lo))
    return pct(0.5), pct(0.25), pct(0.75), float(a[0]), float(a[-1])


class RunData:
    def __init__(self, run: dict, rows: List[dict]):
        self.run = run
        self.rows = rows
        self.task = run["task"]
        self.optimizer = run["optimizer"]
        self.seed = run["seed"]
        best = math.inf
        self.best_curve: List[float] = []
        self.wall: List[float] = []
        self.first_feasible: Optional[int] = None
        self.best_at_wall: Optional[float] = None
        self.best_at: Optional[int] = None
        for k, r in enumerate(rows):
            if r["feasible"] and r["cost"] is not None:
                if self.first_feasible is None:
                    self.first_feasible = k + 1
                if r["cost"] < best:
                    best = r["cost"]
                    self.best_at_wall = r["wall"]
                    self.best_at = k
            self.best_curve.append(best)
            self.wall.append(r["wall"])

    @property
    def best(self) -> float:
        return self.best_curve[-1] if self.best_curve else math.inf

    def best_at_time(self, t: float) -> float:
        k = int(np.searchsorted(np.asarray(self.wall), t, side="right"))
        return self.best_curve[k - 1] if k > 0 else math.inf


def load_runs(db: ExperimentDB) -> List[RunData]:
    out = []
    for run in db.runs():
        rows = db.evaluations(run["run_id"])
        out.append(RunData(run, rows))
    return out


def _groups(runs: List[RunData]) -> Dict[str, Dict[str, List[RunData]]]:
    g: Dict[str, Dict[str, List[RunData]]] = {}
    for r in runs:
        g.setdefault(r.task, {}).setdefault(r.optimizer, []).append(r)
    return g


def _write_csv(path: Path, header: Sequence[str], rows) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in rows:
            w.writerow(r)
    tmp.replace(path)


def write_evaluations_csv(out: Path, runs: List[RunData]) -> Path:
    p = out / "evaluations.csv"

    def rows():
        for rd in runs:
            for k, r in enumerate(rd.rows):
                yield (rd.task, rd.optimizer, rd.seed, k + 1, r["candidate_key"], int(r["feasible"]), r["stage"],
                       _f(r["cost"], None), _f(rd.best_curve[k], None), f"{r['wall']:.4f}", f"{r['eval_seconds']:.4f}")
    _write_csv(p, ("task", "optimizer", "seed", "evaluation", "candidate", "feasible", "stage", "cost", "best_cost",
                   "wall_s", "eval_s"), rows())
    return p


def anytime(groups) -> Tuple[list, list, dict]:
    """Rows of anytime_evals.csv and anytime_time.csv, and the curves for plotting."""
    ev_rows, t_rows, curves = [], [], {}
    for task, by_opt in groups.items():
        for opt, rds in by_opt.items():
            n = max((len(r.best_curve) for r in rds), default=0)
            xs, med, lo, hi = [], [], [], []
            for k in range(n):
                # a finished run keeps its final best for later evaluation counts
                vals = [r.best_curve[min(k, len(r.best_curve) - 1)] for r in rds if r.best_curve]
                m, q1, q3, mn, mx = _stats(vals)
                ev_rows.append((task, opt, k + 1, len(vals), _f(m, 10), _f(q1, 10), _f(q3, 10), _f(mn, 10),
                                _f(mx, 10)))
                xs.append(k + 1)
                med.append(m)
                lo.append(mn)
                hi.append(mx)
            tmax = max((r.wall[-1] for r in rds if r.wall), default=0.0)
            ts = np.linspace(0.0, tmax, TIME_POINTS) if tmax > 0 else np.array([0.0])
            tmed, tlo, thi = [], [], []
            for t in ts:
                vals = [r.best_at_time(t) for r in rds if r.best_curve]
                m, q1, q3, mn, mx = _stats(vals)
                t_rows.append((task, opt, f"{t:.4f}", len(vals), _f(m, 10), _f(q1, 10), _f(q3, 10), _f(mn, 10),
                               _f(mx, 10)))
                tmed.append(m)
                tlo.append(mn)
                thi.append(mx)
            curves[(task, opt)] = {"evals": (xs, med, lo, hi), "time": (list(ts), tmed, tlo, thi)}
    return ev_rows, t_rows, curves


def _changes(v) -> List[int]:
    """Indices where a best-so-far curve becomes finite or improves (marked on the plot)."""
    v = np.asarray(v, dtype=float)
    out = []
    for k in range(len(v)):
        if np.isfinite(v[k]) and (k == 0 or not np.isfinite(v[k - 1]) or v[k] < v[k - 1]):
            out.append(k)
    return out


def cost_axis_label(cost: Optional[str]) -> str:
    """The y axis of an anytime plot: the cost and its unit (``cyc [s]``), from the cost term's description;
    a weighted sum of terms has no single unit (``Liu2 (weighted sum: mechEnergy [J], cyc [s])``)."""
    if not cost:
        return "best cost so far"
    import re

    from robodesign.formats.costs import cost_term, parse_cost
    try:
        terms = parse_cost(cost).terms
    except InputError:  # an old results folder may name a cost this version does not know
        return f"best {cost} so far"

    def unit(name: str) -> str:
        try:
            m = re.search(r"\[([^\]]+)\]\s*$", cost_term(name).description)
        except InputError:  # a term this version does not know
            return ""
        return m.group(1) if m else ""
    if len(terms) == 1 and terms[0][1] == 1:
        u = unit(terms[0][0])
        return f"best {cost} so far" + (f" [{u}]" if u else " (no unit)")
    parts = ", ".join(f"{n} [{unit(n)}]" if unit(n) else n for n, _ in terms)
    return f"best {cost} so far (weighted sum: {parts})"


def plot_task(path: Path, task: str, curves: dict, optimizers: List[str], cost: Optional[str] = None) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), dpi=100)
    any_finite = False
    xmax = {"evals": 1.0, "time": 0.0}
    for opt in optimizers:
        c = curves.get((task, opt))
        if c is None:
            continue
        for ax, key in zip(axes, ("evals", "time")):
            x, med, lo, hi = (np.asarray(v, dtype=float) for v in c[key])
            fin = np.isfinite(med)
            line, = ax.plot(x, np.where(fin, med, np.nan), label=opt, drawstyle="steps-post", lw=1.8,
                            marker="o", ms=3, markevery=_changes(med))
            lo_f = np.where(np.isfinite(lo), lo, np.nan)
            hi_f = np.where(np.isfinite(hi), hi, np.nan)
            hi_f = np.where(np.isnan(hi_f) & np.isfinite(lo_f), lo_f, hi_f)
            ax.fill_between(x, lo_f, hi_f, step="post", alpha=0.18, color=line.get_color(), lw=0)
            ax.plot(x, lo_f, drawstyle="steps-post", lw=0.9, ls="--", color=line.get_color(), marker="o", ms=2,
                    markevery=_changes(lo))  # best seed
            xmax[key] = max(xmax[key], float(x[-1]) if len(x) else 0.0)
            any_finite = any_finite or bool(fin.any()) or bool(np.isfinite(lo).any())
    axes[0].set_xlim(0, max(xmax["evals"], 1.0) + 0.5)
    axes[1].set_xlim(0, max(xmax["time"], 1e-3) * 1.02)
    axes[0].set_xlabel("evaluations")
    axes[1].set_xlabel("wall time [s]")
    for ax in axes:
        ax.set_ylabel(cost_axis_label(cost), fontsize=9)
        ax.grid(True, alpha=0.3)
        if not any_finite:
            ax.text(0.5, 0.5, "no feasible design found yet", ha="center", va="center", transform=ax.transAxes,
                    color="0.4")
    axes[0].set_title("vs evaluations: median (solid), best seed (dashed), min–max", fontsize=10)
    axes[1].set_title("vs wall time: median (solid), best seed (dashed), min–max", fontsize=10)
    handles, labels = axes[0].get_legend_handles_labels()
    if handles:
        axes[0].legend(fontsize=9)
    fig.suptitle(task, fontsize=11)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".tmp.png")
    fig.savefig(tmp, format="png")
    plt.close(fig)
    tmp.replace(path)
    return path


def summarize(groups) -> List[dict]:
    out = []
    for task, by_opt in groups.items():
        for opt, rds in by_opt.items():
            rds = [r for r in rds if r.rows]
            n_eval = sum(len(r.rows) for r in rds)
            bests = [r.best for r in rds]
            solved = [r for r in rds if math.isfinite(r.best)]
            m, _, _, mn, mx = _stats(bests)
            ff = _stats([r.first_feasible if r.first_feasible else math.inf for r in rds])[0]
            tb = _stats([r.best_at_wall for r in solved])[0] if solved else math.inf
            feas = sum(int(x["feasible"]) for r in rds for x in r.rows)
            ev_s = [x["eval_seconds"] for r in rds for x in r.rows]
            best_run = min(solved, key=lambda r: (r.best, r.seed)) if solved else None
            out.append({"task": task, "optimizer": opt, "seeds": len(rds), "evaluations": n_eval,
                        "best_cost_median": m, "best_cost_min": mn, "best_cost_max": mx,
                        "feasible_rate": feas / n_eval if n_eval else math.nan,
                        "seeds_feasible": f"{len(solved)}/{len(rds)}",
                        "evals_to_first_feasible_median": ff, "time_to_best_s_median": tb,
                        "eval_seconds_mean": float(np.mean(ev_s)) if ev_s else math.nan,
                        "best_run": f"{opt}-seed{best_run.seed}" if best_run else ""})
    return out


def _fmt_cell(k: str, v) -> str:
    if isinstance(v, float):
        if not math.isfinite(v):
            return "–"
        if k == "feasible_rate":
            return f"{100 * v:.1f} %"
        if k in ("evals_to_first_feasible_median",):
            return f"{v:g}"
        return f"{v:.4g}"
    return str(v)


def write_summary(out: Path, summary: List[dict]) -> Tuple[Path, Path]:
    pc = out / "summary.csv"
    _write_csv(pc, SUMMARY_COLUMNS, ([_f(s[c], 10) if isinstance(s[c], float) else s[c] for c in SUMMARY_COLUMNS]
                                     for s in summary))
    lines = ["# Summary", "",
             "Best cost over seeds (a seed without a feasible design counts as +inf), share of feasible "
             "evaluations, seeds that found a feasible design, median evaluations to the first feasible design "
             "and median wall time to the final best.", ""]
    by_task: Dict[str, List[dict]] = {}
    for s in summary:
        by_task.setdefault(s["task"], []).append(s)
    cols = [c for c in SUMMARY_COLUMNS if c != "task"]
    for task, rows in by_task.items():
        lines += [f"## {task}", "", "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
        rows = sorted(rows, key=lambda s: (s["best_cost_median"], s["best_cost_min"]))
        for s in rows:
            lines.append("| " + " | ".join(_fmt_cell(c, s[c]) for c in cols) + " |")
        lines.append("")
    pm = out / "summary.md"
    pm.write_text("\n".join(lines))
    return pc, pm


def _best_robots(db: ExperimentDB) -> List[dict]:
    out = []
    for (task,) in db.con.execute("SELECT DISTINCT task FROM runs ORDER BY ordinal").fetchall():
        row = db.con.execute(
            "SELECT e.run_id, e.idx, e.candidate_key, e.module_order, e.base, e.cost, e.solution, r.optimizer, r.seed "
            "FROM evaluations e JOIN runs r USING (run_id) WHERE r.task=? AND e.feasible=1 AND e.cost IS NOT NULL "
            "ORDER BY e.cost, r.ordinal, e.idx LIMIT 1", (task,)).fetchone()
        if row is None:
            out.append({"task": task})
            continue
        sol = json.loads(row["solution"]) if row["solution"] else {}
        bp = (sol.get("basePose") or [None])[0]
        out.append({"task": task, "optimizer": row["optimizer"], "seed": row["seed"], "cost": row["cost"],
                    "order": json.loads(row["module_order"]), "base": json.loads(row["base"]),
                    "base_pose": bp, "cost_function": sol.get("costFunction")})
    return out


def best_solution_path(b: dict) -> str:
    """The best solution file of a "Best robots" row, relative to the results folder (runner.best_paths)."""
    return f"best/{b['task']}/{b['optimizer']}-seed{b['seed']}.json"


def base_pose_text(bp) -> str:
    """A base pose (4×4, nested lists or an array) as ``xyz = (x, y, z) m, yaw = ψ°``; "nominal" for none."""
    if bp is None or np.size(bp) == 0:
        return "nominal"
    T = np.asarray(bp, dtype=float)
    if T.shape != (4, 4):
        return str(bp)
    yaw = math.degrees(math.atan2(T[1, 0], T[0, 0]))
    x, y, z = (_mm(v) for v in T[:3, 3])
    return f"xyz = ({x}, {y}, {z}) m, yaw = {_deg(yaw)}°"


def _mm(v: float) -> str:
    """A length in m to a tenth of a millimetre, without a negative zero."""
    return f"{round(float(v), 4) + 0.0:.4f}"


def search_offsets_text(params) -> str:
    """A design's base search parameters (offsets from the nominal base: metres, the yaw in radians) with
    the precision of :func:`base_pose_text`."""
    return "[" + ", ".join(_mm(x) for x in params) + "]"


def _deg(v: float) -> str:
    """An angle in degrees to a tenth, without a negative zero."""
    return f"{round(float(v), 1) + 0.0:.1f}"


def view_path(solution_rel: str) -> str:
    """``best/t/random-seed0.json`` → ``best/t/random-seed0_view.html`` (relative to the results folder)."""
    return solution_rel[:-len(".json")] + "_view.html"


def write_views(out: Path, meta: dict, solutions: Sequence[str], verdicts: Dict[str, dict]) -> Dict[str, str]:
    """Write the 3-D view page of each best solution (paths relative to ``out``, in priority order; at most
    :data:`VIEW_PAGES_MAX`); returns ``{solution: view page}`` for the pages that exist. A page newer than
    its solution is kept (a resumed experiment does not redo it); one that cannot be built is left out."""
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.solution import load_solution
    from robodesign.formats.task_io import load_task
    from robodesign.viewer import solution_page
    problems = {p.get("name"): p for p in meta.get("problems", [])}
    views: Dict[str, str] = {}
    for rel in list(dict.fromkeys(solutions))[:VIEW_PAGES_MAX]:
        sol_file, page = out / rel, out / view_path(rel)
        if not sol_file.is_file():
            continue
        if not page.is_file() or page.stat().st_mtime < sol_file.stat().st_mtime:
            task_name = str(Path(rel).parent.relative_to("best"))
            prob = problems.get(task_name, {})
            try:
                task = load_task(prob["task"]) if prob.get("task") else None
                ms = load_module_set(prob["modules"]) if prob.get("modules") else None
                html_page = solution_page(task, load_solution(sol_file), ms, verdict=verdicts.get(rel), plots=False,
                                          title=f"{task_name}: {Path(rel).stem}")
            except Exception:  # noqa: BLE001 - a missing asset costs the link, never the report
                continue
            tmp = page.with_suffix(".html.tmp")
            tmp.write_text(html_page, encoding="utf-8")
            tmp.replace(page)
        views[rel] = view_path(rel)
    return views


_CSS = ("body{font-family:system-ui,sans-serif;margin:2em;max-width:1200px}"
        ".tbl{max-width:100%;overflow-x:auto;margin:.5em 0 1.5em}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:3px 8px;font-size:13px;text-align:right}"
        "th{background:#f3f3f3;vertical-align:bottom}td:first-child,td:nth-child(2){text-align:left}"
        "code{font-size:12px;overflow-wrap:anywhere}img{max-width:100%;border:1px solid #eee}"
        ".bad{color:#b00}.ok{color:#070}")


def _th(name: str) -> str:
    """A header cell that may wrap after each ``_`` (long column names stay readable in narrow tables)."""
    return f"<th>{html.escape(name).replace('_', '_<wbr>')}</th>"


def write_index(out: Path, meta: dict, summary: List[dict], plots: Dict[str, str], best: List[dict],
                verdicts: List[dict], suites_html: str = "", views: Optional[Dict[str, str]] = None) -> Path:
    e = html.escape
    views = views or {}

    def view_link(sol: str) -> str:
        return f" · <a href='{e(views[sol])}'>3D view</a>" if sol in views else ""

    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{e(meta.get('name', 'experiment'))}</title>",
             f"<style>{_CSS}</style></head><body>",
             f"<h1>Experiment {e(meta.get('name', ''))}</h1>"]
    m = meta.get("machine", {})
    v = meta.get("versions", {})
    parts.append(f"<p>created {e(str(meta.get('created', '')))} · seeds {e(str(meta.get('seeds')))} · "
                 f"{e(str(m.get('cpu', '')))}, {m.get('cores')} cores, {m.get('memory_gib')} GiB · Python "
                 f"{e(str(m.get('python')))} · robodesign {e(str(v.get('robodesign')))}</p>")
    parts.append("<p>Files: <a href='summary.csv'>summary.csv</a> · <a href='summary.md'>summary.md</a> · "
                 "<a href='evaluations.csv'>evaluations.csv</a> · <a href='anytime_evals.csv'>anytime_evals.csv</a> · "
                 "<a href='anytime_time.csv'>anytime_time.csv</a> · <a href='meta.json'>meta.json</a> · "
                 "<a href='config.yaml'>config.yaml</a> · evaluations.sqlite"
                 + (" · <a href='suites.csv'>suites.csv</a> · <a href='suites.md'>suites.md</a>" if suites_html else "")
                 + "</p>")
    parts.append(suites_html)
    parts.append("<h2>Best robots</h2><table><tr><th>task</th><th>optimizer</th><th>seed</th><th>cost</th>"
                 "<th>module order</th><th>base pose</th><th>files</th></tr>")
    for b in best:
        if "cost" not in b:
            parts.append(f"<tr><td>{e(b['task'])}</td><td colspan=6>no feasible design found</td></tr>")
            continue
        sol = best_solution_path(b)
        parts.append(f"<tr><td>{e(b['task'])}</td><td>{e(b['optimizer'])}</td><td>{b['seed']}</td>"
                     f"<td>{b['cost']:.6g} ({e(str(b.get('cost_function') or ''))})</td>"
                     f"<td><code>{e(','.join(b['order']))}</code></td><td>{e(base_pose_text(b.get('base_pose')))}</td>"
                     f"<td><a href='{e(sol)}'>solution</a> · <a href='{e(sol[:-5] + '.verdict.json')}'>verdict</a>"
                     f"{view_link(sol)}</td></tr>")
    parts.append("</table>")
    cols = list(SUMMARY_COLUMNS)
    by_task: Dict[str, List[dict]] = {}
    for s in summary:
        by_task.setdefault(s["task"], []).append(s)
    for task, rows in by_task.items():
        parts.append(f"<h2>{e(task)}</h2><table><tr>" + "".join(_th(c) for c in cols[1:]) + "</tr>")
        for s in sorted(rows, key=lambda s: (s["best_cost_median"], s["best_cost_min"])):
            parts.append("<tr>" + "".join(f"<td>{e(_fmt_cell(c, s[c]))}</td>" for c in cols[1:]) + "</tr>")
        parts.append("</table>")
        if task in plots:
            parts.append(f"<img src='{e(plots[task])}' alt='anytime curves of {e(task)}'>")
    if verdicts:
        parts.append("<h2>Checked best solutions</h2><table><tr><th>file</th><th>verdict</th><th>cost (checker)</th>"
                     "<th>cost (stored)</th><th>agrees</th></tr>")
        for vd in verdicts:
            ok = vd.get("valid")
            said = "VALID" if ok else "INVALID" if ok is not None else f"ERROR ({vd.get('error', 'not checked')})"
            parts.append(f"<tr><td><a href='{e(vd['path'])}'>{e(vd['path'])}</a>{view_link(vd['path'])}</td>"
                         f"<td class='{'ok' if ok else 'bad'}'>{e(said)}</td>"
                         f"<td>{_f(vd.get('cost'))}</td><td>{_f(vd.get('cost_stored'))}</td>"
                         f"<td class='{'ok' if vd.get('agrees') else 'bad'}'>{'yes' if vd.get('agrees') else 'NO'}</td>"
                         f"</tr>")
        parts.append("</table>")
    sess = meta.get("sessions", [])
    if sess:
        parts.append("<h2>Sessions</h2><table><tr><th>started</th><th>finished</th><th>status</th><th>executor</th>"
                     "<th>new evaluations</th></tr>")
        for s in sess:
            ex = s.get("executor") or {}
            parts.append(f"<tr><td>{e(str(s.get('started', '')))}</td><td>{e(str(s.get('finished', '')))}</td>"
                         f"<td>{e(str(s.get('status', 'running or killed')))}</td>"
                         f"<td>{e(str(ex.get('kind', '')))} × {ex.get('workers', '')}</td>"
                         f"<td>{s.get('new_evaluations', '')}</td></tr>")
        parts.append("</table>")
    parts.append("</body></html>")
    p = out / "index.html"
    tmp = p.with_suffix(".html.tmp")
    page = "\n".join(parts)  # every table (the suites' too) scrolls inside its own box, never the page
    tmp.write_text(page.replace("<table", "<div class='tbl'><table").replace("</table>", "</table></div>"),
                   encoding="utf-8")
    tmp.replace(p)
    return p


def write_suites(out: Path, meta: dict, db: ExperimentDB) -> str:
    """``suites.csv``, ``suites_unsolved.csv``, ``suites_tasks.csv`` and ``suites.md`` when the experiment has
    suites (every unsolved run diagnosed: provably out of reach or not found); returns the HTML tables for
    the report page ("" without suites)."""
    from robodesign.experiment.suites import (
        SUITE_COLUMNS,
        TASK_COLUMNS,
        UNSOLVED_COLUMNS,
        html_tables,
        markdown,
        problems_of,
        records_from_db,
        suite_of_problems,
        summarize_suites,
        task_rows,
        unsolved_rows,
    )
    suite_of = suite_of_problems(meta)
    if not suite_of:
        return ""
    recs = records_from_db(db, suite_of, problems_of(meta))
    summary, unsolved, tasks = summarize_suites(recs), unsolved_rows(recs), task_rows(recs)
    _write_csv(out / "suites.csv", SUITE_COLUMNS, ([_f(s[c], 10) if isinstance(s[c], float) else s[c]
                                                    for c in SUITE_COLUMNS] for s in summary))
    _write_csv(out / "suites_unsolved.csv", UNSOLVED_COLUMNS, ([u[c] for c in UNSOLVED_COLUMNS] for u in unsolved))
    _write_csv(out / "suites_tasks.csv", TASK_COLUMNS, ([_f(t[c], 10) if isinstance(t[c], float) else t[c]
                                                        for c in TASK_COLUMNS] for t in tasks))
    (out / "suites.md").write_text(markdown(summary, unsolved, tasks))
    return html_tables(summary, unsolved)


def write_report(out: Path, db: Optional[ExperimentDB] = None) -> Path:
    """Write every report file of a results folder; returns the path of ``index.html``."""
    out = Path(out)
    own = db is None
    db = db or ExperimentDB(out / "evaluations.sqlite")
    try:
        meta = json.loads((out / "meta.json").read_text()) if (out / "meta.json").exists() else {}
        runs = load_runs(db)
        groups = _groups(runs)
        write_evaluations_csv(out, runs)
        ev_rows, t_rows, curves = anytime(groups)
        head = ("n_seeds", "median", "q25", "q75", "min", "max")
        _write_csv(out / "anytime_evals.csv", ("task", "optimizer", "evaluation") + head, ev_rows)
        _write_csv(out / "anytime_time.csv", ("task", "optimizer", "time_s") + head, t_rows)
        plots = {}
        costs = {p.get("name"): p.get("cost") for p in meta.get("problems", []) if isinstance(p, dict)}
        for task, by_opt in groups.items():
            p = plot_task(out / "plots" / f"{_slug(task)}.png", task, curves, list(by_opt), costs.get(task))
            plots[task] = str(p.relative_to(out))
        summary = summarize(groups)
        write_summary(out, summary)
        verdicts = []
        for vp in sorted((out / "best").rglob("*.verdict.json")) if (out / "best").is_dir() else []:
            try:
                vd = json.loads(vp.read_text())
            except ValueError:
                continue
            vd["path"] = str(vp.with_name(vp.name.replace(".verdict.json", ".json")).relative_to(out))
            verdicts.append(vd)
        best = _best_robots(db)
        firsts = [best_solution_path(b) for b in best if "cost" in b]
        views = write_views(out, meta, firsts + [vd["path"] for vd in verdicts], {vd["path"]: vd for vd in verdicts})
        return write_index(out, meta, summary, plots, best, verdicts, write_suites(out, meta, db), views)
    finally:
        if own:
            db.close()
