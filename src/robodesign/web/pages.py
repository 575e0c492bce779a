"""Server-rendered HTML pages of the benchmark website (no templates engine, no external resources).

Every value that comes from a file or a user goes through :func:`e` (``html.escape``).
"""
from __future__ import annotations

import json
from html import escape
from typing import Iterable, List, Optional
from urllib.parse import quote

from robodesign.web import db

CSS = """
:root { --fg:#1d2430; --muted:#5b6577; --line:#d9dee7; --bg:#f6f7f9; --accent:#1f5fbf; --ok:#1c7c3c; --bad:#b42318; }
* { box-sizing: border-box; }
body { margin:0; font:15px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color:var(--fg);
       background:var(--bg); }
header { background:#16202f; color:#fff; padding:.7rem 1.5rem; display:flex; gap:1.5rem; align-items:center; }
header a { color:#dbe6ff; text-decoration:none; } header a:hover { text-decoration:underline; }
header .brand { font-weight:700; color:#fff; font-size:1.1rem; }
main { max-width:1100px; margin:1.5rem auto; padding:0 1.5rem; }
h1 { font-size:1.5rem; margin:.2rem 0 1rem; } h2 { font-size:1.15rem; margin:1.6rem 0 .6rem; }
a { color:var(--accent); }
table { border-collapse:collapse; width:100%; background:#fff; border:1px solid var(--line); margin-bottom:1rem; }
th, td { text-align:left; padding:.4rem .6rem; border-bottom:1px solid var(--line); vertical-align:top;
         overflow-wrap:anywhere; }
th { background:#eef1f6; font-weight:600; font-size:.9rem; }
td.num, th.num { text-align:right; font-variant-numeric: tabular-nums; overflow-wrap:normal; white-space:nowrap; }
code, .mono { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; font-size:.88rem; }
.muted { color:var(--muted); } .small { font-size:.85rem; }
.card { background:#fff; border:1px solid var(--line); border-radius:6px; padding:1rem 1.2rem; margin-bottom:1rem; }
.ok { color:var(--ok); font-weight:600; } .bad { color:var(--bad); font-weight:600; }
.banner-ok { border-left:5px solid var(--ok); } .banner-bad { border-left:5px solid var(--bad); }
form.stack label { display:block; margin:.6rem 0 .2rem; font-weight:600; }
form.stack input[type=text], form.stack input[type=email], form.stack input[type=password], form.stack select {
  width:100%; max-width:32rem; padding:.4rem; border:1px solid var(--line); border-radius:4px; font:inherit; }
button { background:var(--accent); color:#fff; border:0; border-radius:4px; padding:.5rem 1rem; font:inherit;
         cursor:pointer; margin-top:.8rem; }
form.inline select { padding:.35rem; border:1px solid var(--line); border-radius:4px; font:inherit; max-width:16rem; }
form.inline button { margin-top:0; margin-left:.4rem; }
.links a { display:block; overflow-wrap:anywhere; }  /* long collaborative benchmark IDs wrap, never scroll */
.grid { display:grid; grid-template-columns: repeat(auto-fill, minmax(15rem, 1fr)); gap:.3rem .8rem; }
iframe.viewer { width:100%; height:560px; border:1px solid var(--line); background:#fff; }
.rank1 td { background:#fff8e1; }
.tag { display:inline-block; background:#eef1f6; border-radius:3px; padding:0 .35rem; margin-right:.2rem;
       font-size:.8rem; }
"""


def e(x) -> str:
    return escape("" if x is None else str(x), quote=True)


def fmt_cost(c) -> str:
    return "—" if c is None else f"{c:.6g}"


def bid_url(bid: str) -> str:
    return "/leaderboard/" + quote(bid, safe="/:-_.,")


def task_url(tid: str) -> str:
    return "/tasks/" + quote(tid, safe="/-_.")


def benchmark_id_for(module_set: str, cost: str, tid: str, n_robots: int = 0) -> str:
    """``M-<set>:<cost>:<task>``; for a collaborative task of ``n_robots`` the same set for every robot
    ``[M-<set>,M-<set>]:<cost>:<task>``."""
    robot = f"[{','.join(['M-' + module_set] * n_robots)}]" if n_robots else f"M-{module_set}"
    return f"{robot}:{cost}:{tid}"


def fmt_tuple(costs) -> str:
    return "(" + ", ".join(fmt_cost(c) for c in costs or []) + ")"


def robots_of(row: db.TaskRow) -> list:
    try:
        return json.loads(row.robots or "[]")
    except (ValueError, TypeError):
        return []


def layout(title: str, body: str) -> str:
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>{e(title)} · robodesign benchmark</title><link rel="stylesheet" href="/static/style.css"></head>
<body><header><a class="brand" href="/">robodesign benchmark</a><a href="/">Benchmarks</a>
<a href="/upload">Upload a solution</a><a href="/api/tasks">API</a></header>
<main>{body}</main></body></html>"""


def table(head: List[str], rows: Iterable[List[str]], num_cols=(), row_class=None) -> str:
    h = "".join(f'<th class="num">{x}</th>' if i in num_cols else f"<th>{x}</th>" for i, x in enumerate(head))
    out = []
    for k, r in enumerate(rows):
        cls = f' class="{row_class(k)}"' if row_class and row_class(k) else ""
        out.append(f"<tr{cls}>" + "".join(f'<td class="num">{x}</td>' if i in num_cols else f"<td>{x}</td>"
                                          for i, x in enumerate(r)) + "</tr>")
    if not out:
        out = [f'<tr><td colspan="{len(head)}" class="muted">none yet</td></tr>']
    return f"<table><thead><tr>{h}</tr></thead><tbody>{''.join(out)}</tbody></table>"


def tags(js: str) -> str:
    try:
        return "".join(f'<span class="tag">{e(t)}</span>' for t in json.loads(js))
    except (ValueError, TypeError):
        return ""


def index(tasks: List[db.TaskRow], msets: List[db.ModuleSetRow], costs: List[db.CostFunctionRow],
          benchmarks: List[dict]) -> str:
    first_set = msets[0].name if msets else "<set>"
    bench_rows = [[f'<a class="mono" href="{e(bid_url(b["benchmark_id"]))}">{e(b["benchmark_id"])}</a>',
                   str(b["solutions"]), fmt_cost(b["best_cost"]) + (" <span class=\"muted small\">total</span>"
                                                                   if b.get("collaborative") else "")]
                  for b in benchmarks]
    task_rows = []
    for t in tasks:
        n = len(robots_of(t))
        bids = [benchmark_id_for(m.name, "cyc", t.task_id, n) for m in msets]
        task_rows.append([f'<a class="mono" href="{e(task_url(t.task_id))}">{e(t.task_id)}</a>'
                          + (f' <span class="tag collab">collaborative: {n} robots</span>' if n else ""),
                          e(t.name), tags(t.tags), str(t.n_goals), str(t.n_obstacles),
                          '<div class="links">' + "".join(f'<a class="mono small" href="{e(bid_url(b))}">{e(b)}</a>'
                                                          for b in bids) + "</div>"])
    set_rows = [[f'<a class="mono" href="/modulesets/{e(quote(m.name))}">{e(m.name)}</a>',
                 str(len(json.loads(m.module_ids or "[]"))), e(m.origin)] for m in msets]
    cost_rows = [[f"<code>{e(c.name)}</code>", f"<code>{e(c.descriptor)}</code>", e(c.description)] for c in costs]
    def opt(values):
        return "".join(f'<option value="{e(v)}">{e(v)}</option>' for v in values)
    body = f"""<h1>Benchmarks</h1>
<p class="muted">A benchmark ID <code>M-&lt;module set&gt;:&lt;cost&gt;:&lt;task&gt;</code> names a task, the module set
the robot is assembled from and the cost to minimise, e.g. <code>M-{e(first_set)}:cyc:simple/PTP_1</code>.
A collaborative task (several robots in one cell) has IDs with one module set and cost per robot,
<code>[M-&lt;set 1&gt;,M-&lt;set 2&gt;]:[&lt;cost 1&gt;,&lt;cost 2&gt;]:&lt;task&gt;</code>.
Every uploaded solution is checked by the robodesign checker; leaderboards rank valid solutions by cost (lower is better;
collaborative: by the total cost, ties by the tuple of the robots' costs).</p>
<div class="card"><form class="inline" method="get" action="/leaderboard">
<b>Open a leaderboard:</b> M-<select name="moduleset" aria-label="module set">{opt(m.name for m in msets)}</select>
: <select name="cost" aria-label="cost">{opt(c.name for c in costs)}</select>
: <select name="task" aria-label="task">{opt(t.task_id for t in tasks)}</select>
<button type="submit">Show</button></form></div>
<h2>Benchmarks with solutions</h2>
{table(["Benchmark ID", "Solutions", "Best cost"], bench_rows, num_cols=(1, 2))}
<h2>Tasks</h2>
{table(["Task ID", "Name", "Tags", "Goals", "Obstacles", "Benchmarks (cycle time)"], task_rows, num_cols=(3, 4))}
<h2>Module sets</h2>
{table(["Module set", "Modules", "Origin"], set_rows, num_cols=(1,))}
<h2>Cost functions</h2>
{table(["Name", "CoBRA descriptor", "Description"], cost_rows)}"""
    return layout("Benchmarks", body)


def task_page(row: db.TaskRow, parsed, msets: List[db.ModuleSetRow], costs: List[db.CostFunctionRow],
              count, warnings: Iterable[str] = ()) -> str:
    """``parsed``: the Task, or the CollabTask of a collaborative task; ``count(benchmark ID)``: its solutions."""
    ctask = parsed if hasattr(parsed, "robot_ids") else None
    task = ctask.task if ctask else parsed
    n_robots = len(ctask.robot_ids) if ctask else 0
    h = task.header
    goals = [[f"<code>{e(g.id)}</code>", e(type(g).__name__), e(", ".join(type(c).__name__ for c in g.constraints))]
             + ([e(ctask.assignment[g.id] or "any robot")] if ctask else []) for g in task.goals]
    cons = [[e(type(c).__name__), f"<code>{e(_short(c))}</code>"] for c in task.constraints]
    obstacles = [[f"<code>{e(o.id)}</code>", e(o.name), str(len(o.collision)),
                  "moving" if getattr(o, "motion_t", None) is not None else "static"] for o in task.obstacles]
    assets = json.loads(row.assets or "[]")
    asset_rows = [[f"<code>{e(a['path'])}</code>", str(a["size"]), f'<code class="small">{e(a["sha256"][:16])}…</code>']
                  for a in assets]
    grid = []
    for m in msets:
        links = []
        for c in costs:
            bid = benchmark_id_for(m.name, c.name, row.task_id, n_robots)
            n = count(bid)
            links.append(f'<a class="mono small" title="{e(bid)}" href="{e(bid_url(bid))}">{e(c.name)}</a>'
                         + (f' <b>({n})</b>' if n else ""))
        grid.append(f'<tr><td class="mono small">{e(benchmark_id_for(m.name, "<cost>", row.task_id, n_robots))}</td>'
                    f'<td class="costs">{" · ".join(links)}</td></tr>')
    robots = ""
    if ctask:
        rrows = []
        for rid in ctask.robot_ids:
            base = ctask.robot_tasks[rid].nominal_base_pose
            rrows.append([f"<code>{e(rid)}</code>", e(ctask.robot_names[rid]),
                          e("(" + ", ".join(f"{x:.3g}" for x in base[:3, 3]) + ")"),
                          e(", ".join(ctask.goals_of(rid)) or "—")])
        robots = f"""<h2>Robots</h2><p class="muted small">A collaborative task: the robots share the cell, each with
its own module set, base, trajectory and cost; goals marked "any robot" may be achieved by either
(docs/collaborative.md).</p>{table(["ID", "Name", "Base position [m]", "Its goals"], rrows)}"""
    warn = "".join(f'<li class="small">{e(w)}</li>' for w in warnings)
    kind = f' <span class="tag collab">collaborative: {n_robots} robots</span>' if ctask else ""
    body = f"""<h1>Task <code>{e(row.task_id)}</code>{kind}</h1>
<div class="card"><b>{e(h.name or row.task_id)}</b> {tags(row.tags)}<br>
<span class="muted small">version {e(h.version)} · {e(h.date)} · {e(", ".join(h.author))}
{(" · " + e(", ".join(h.affiliation))) if h.affiliation else ""} · time step {h.time_step:g} s ·
gravity {e(list(h.gravity))}</span><br>
<a class="small" href="/api/tasks/{e(quote(row.task_id, safe="/-_."))}">task JSON</a>
{f'<ul>{warn}</ul>' if warn else ''}</div>
{robots}<h2>Goals</h2>{table(["ID", "Type", "Goal constraints"] + (["Robot"] if ctask else []), goals)}
<h2>Constraints</h2>{table(["Type", "Details"], cons)}
<h2>Obstacles</h2>{table(["ID", "Name", "Collision geometries", "Motion"], obstacles, num_cols=(2,))}
<h2>Stored assets</h2>{table(["File", "Bytes", "SHA-256"], asset_rows, num_cols=(1,))}
<h2>Benchmark IDs</h2><p class="muted small">One leaderboard per module set and cost; solutions so far in
bold.</p><table><thead><tr><th>Benchmark ID</th><th>Cost (leaderboard)</th></tr></thead>
<tbody>{''.join(grid) or '<tr><td colspan="2" class="muted">no module sets</td></tr>'}</tbody></table>"""
    return layout(f"Task {row.task_id}", body)


def _short(c) -> str:
    out = []
    for k, v in getattr(c, "__dict__", {}).items():
        if k.startswith("_") or v is None:
            continue
        if isinstance(v, frozenset):
            v = ",".join(sorted(v))
        elif isinstance(v, tuple):
            v = ",".join(str(x) for x in v)
        elif not isinstance(v, (str, int, float)):
            v = type(v).__name__
        out.append(f"{k}={v}")
    return ", ".join(out)[:160]


def moduleset_page(row: db.ModuleSetRow, ms) -> str:
    rows = []
    for mid, m in ms.modules.items():
        mass = sum(b.mass for b in m.bodies)
        rows.append([f"<code>{e(mid)}</code>", e(m.header.name), str(len(m.bodies)), str(len(m.joints)),
                     f"{mass:.3f}"])
    assets = json.loads(row.assets or "[]")
    body = f"""<h1>Module set <code>{e(row.name)}</code></h1>
<p class="muted">{len(ms.modules)} modules · {len(assets)} stored mesh files ·
<a href="/api/modulesets/{e(quote(row.name))}">modules.json</a></p>
{table(["ID", "Name", "Bodies", "Joints", "Mass [kg]"], rows, num_cols=(2, 3, 4))}"""
    return layout(f"Module set {row.name}", body)


def leaderboard(board, rows: List[db.SolutionRow]) -> str:
    """``board``: the service's Board (display ID, task, module sets, collaborative or not)."""
    bid, tid, collab = board.display, board.task_id, board.collaborative
    trs = []
    for k, r in enumerate(rows):
        link = f'<a href="/solutions/{r.id}">#{r.id}</a>'
        if collab:
            link += f' · <a class="small" href="/solutions/{r.id}/viewer">3D</a>'
        trs.append([str(k + 1), f"<b>{fmt_cost(r.cost)}</b>"]
                   + ([f'<span class="mono">{e(fmt_tuple(json.loads(r.cost_tuple or "[]")))}</span>'] if collab else [])
                   + [e(r.author_name), e(r.author_affiliation), str(r.n_modules), str(r.dof),
                      e(r.created.strftime("%Y-%m-%d %H:%M")), link])
    sets = ", ".join(f'<a href="/modulesets/{e(quote(m))}">{e(m)}</a>' for m in dict.fromkeys(board.module_sets))
    if collab:
        head = ["Rank", "Total cost", "Cost tuple (per robot)"]
        order = ("collaborative: valid solutions ranked by total cost (the sum of the robots' costs), ties broken by "
                 "the cost tuple compared robot by robot, then the earlier upload")
    else:
        head, order = ["Rank", "Cost"], "valid solutions ranked by cost (ascending)"
    n = len(head)
    body = f"""<h1>Leaderboard</h1>
<p><code class="mono" id="benchmark-id">{e(bid)}</code></p>
<p class="muted">Task <a href="{e(task_url(tid))}">{e(tid)}</a> · module set{"s" if collab else ""} {sets} ·
{order} · <a href="/api/leaderboard/{e(quote(bid, safe='/:-_.,'))}">JSON</a> · <a href="/upload">upload a
solution</a></p>
{table(head + ["Author", "Affiliation", "Modules", "Joints", "Uploaded (UTC)", "Solution"], trs,
       num_cols=tuple(range(2)) + (n + 2, n + 3), row_class=lambda k: "rank1" if k == 0 else "")}"""
    return layout(f"Leaderboard {bid}", body)


def robot_results(verdict: dict) -> str:
    """The per-robot part of a collaborative verdict: each robot's cost function, cost, goals and violations."""
    rows = []
    cfs, costs = verdict.get("costFunctions") or [], verdict.get("costs") or []
    for k, (rid, v) in enumerate((verdict.get("robots") or {}).items()):
        cost = costs[k] if k < len(costs) else None
        goals = ", ".join(f"{g}: {'ok' if ok else 'missed'}" for g, ok in (v.get("goals") or {}).items())
        nviol = len(v.get("violations") or [])
        rows.append([f"<code>{e(rid)}</code>", f"<code>{e(cfs[k] if k < len(cfs) else '')}</code>",
                     fmt_cost(cost), e(goals or "—"),
                     '<span class="ok">valid</span>' if v.get("valid") else f'<span class="bad">{nviol} violation(s)</span>'])
    by = ", ".join(f"{g}: {r or 'nobody'}" for g, r in (verdict.get("goals") or {}).items())
    return (table(["Robot", "Cost function", "Cost", "Goals", "Verdict"], rows, num_cols=(2,))
            + f'<p class="small">cost tuple <b class="mono" id="cost-tuple">{e(fmt_tuple(verdict.get("costs")))}</b>'
              f' · total cost <b id="total-cost">{fmt_cost(verdict.get("totalCost"))}</b>'
              f'{" · goals achieved by " + e(by) if by else ""}</p>')


def collab_viewer_verdict(verdict: Optional[dict]) -> Optional[dict]:
    """A collaborative verdict in the form the viewer lists (valid, total cost, violations with their robot)."""
    if not verdict:
        return None
    return {"valid": verdict.get("valid"), "cost": verdict.get("totalCost"),
            "costFunction": "total cost " + fmt_tuple(verdict.get("costs")),
            "violations": [{**x, "message": f"[{x.get('robot') or 'cell'}] {x.get('message')}"}
                           for x in verdict.get("violations") or []]}


def solution_page(row: db.SolutionRow, viewer: bool, viewer_note: str = "") -> str:
    v = json.loads(row.verdict_json or "{}")
    if row.collaborative:  # the costs of every robot, one column each
        rids = list(v.get("robots") or {})
        per = [(v["robots"][r].get("costs") or {}) for r in rids]
        names = list(dict.fromkeys(k for p in per for k in p))
        costs = [[f"<code>{e(k)}</code>"] + [fmt_cost(p.get(k)) for p in per] for k in names]
        cost_head = ["Cost"] + [f"robot {e(r)}" for r in rids]
        goals = ", ".join(f"{e(g)}: {e(r or 'missed')}" for g, r in (v.get("goals") or {}).items())
    else:
        costs = [[f"<code>{e(k)}</code>", fmt_cost(c)] for k, c in (v.get("costs") or {}).items()]
        cost_head = ["Cost", "Value"]
        goals = ", ".join(f"{e(g)}: {'ok' if ok else 'missed'}" for g, ok in (v.get("goals") or {}).items())
    status = ('<span class="bad">withdrawn</span>' if row.withdrawn else '<span class="ok">valid</span>')
    frame = (f'<iframe class="viewer" title="3D viewer" src="/solutions/{row.id}/viewer" '
             f'sandbox="allow-scripts" loading="eager"></iframe>' if viewer
             else f'<p class="muted">{e(viewer_note or "The 3D viewer is not available on this server.")}</p>')
    body = f"""<h1>Solution #{row.id}</h1>
<div class="card"><code class="mono">{e(row.benchmark_id)}</code> — {status}<br>
{"total " if row.collaborative else ""}cost <b id="cost">{fmt_cost(row.cost)}</b> ({e(row.cost_function)}) · by {e(row.author_name)}
{(" · " + e(row.author_affiliation)) if row.author_affiliation else ""} · uploaded
{e(row.created.strftime("%Y-%m-%d %H:%M"))} UTC<br>
<span class="small">goals: {goals or "—"} · {row.n_modules} modules, {row.dof} joints ·
<a href="{e(bid_url(row.benchmark_id))}">leaderboard</a> · <a href="/api/solutions/{row.id}/json">solution JSON</a> ·
<a href="/api/solutions/{row.id}">verdict JSON</a></span></div>
{"<h2>Robots</h2>" + robot_results(v) if row.collaborative else ""}
<h2>3D view</h2>{frame}{f'<p class="small"><a href="/solutions/{row.id}/viewer">open the 3D view on its own page</a></p>'
                        if viewer else ""}
<h2>Costs</h2>{table(cost_head, costs, num_cols=tuple(range(1, len(cost_head))))}
{'' if row.withdrawn else f'''<h2>Withdraw</h2><form class="stack" method="post" action="/solutions/{row.id}/withdraw">
<label for="tok">Your token</label><input id="tok" type="password" name="token" required autocomplete="off">
<button type="submit">Withdraw this solution</button></form>'''}"""
    return layout(f"Solution {row.id}", body)


def upload_form(msg: str = "", values: Optional[dict] = None) -> str:
    v = values or {}
    body = f"""<h1>Upload a solution</h1>{msg}
<div class="card"><form class="stack" method="post" action="/upload" enctype="multipart/form-data">
<label for="file">Solution file (CoBRA solution JSON)</label>
<input id="file" type="file" name="file" accept=".json,application/json" required>
<label for="author">Author name</label><input id="author" type="text" name="author" required maxlength="200"
 value="{e(v.get('author'))}">
<label for="email">Email (optional, not shown publicly)</label><input id="email" type="email" name="email"
 maxlength="200" value="{e(v.get('email'))}">
<label for="affiliation">Affiliation (optional)</label><input id="affiliation" type="text" name="affiliation"
 maxlength="300" value="{e(v.get('affiliation'))}">
<label for="token">Token (optional: reuse your own secret to manage several uploads; empty = a new random one)</label>
<input id="token" type="password" name="token" maxlength="200" autocomplete="off">
<button type="submit">Check and upload</button></form></div>
<p class="muted small">The solution names its task (<code>taskID</code>), module set (<code>moduleSet</code>) and cost
(<code>costFunction</code>); together they form its benchmark ID. Tasks and module sets are added through the API
(<code>POST /api/tasks</code>, <code>POST /api/modulesets</code>).</p>"""
    return layout("Upload", body)


def upload_result(res) -> str:
    collab = res.collaborative
    robots = robot_results(res.verdict) if collab else ""
    if res.valid:
        view = (f' · <a href="/solutions/{res.id}/viewer">watch the robots move together</a>' if collab else "")
        msg = f"""<div class="card banner-ok" id="result"><p class="ok">Valid — accepted as solution #{res.id}.</p>
<p>Benchmark <a class="mono" href="{e(bid_url(res.benchmark_id))}">{e(res.benchmark_id)}</a>, {"total " if collab else ""}cost
<b id="result-cost">{fmt_cost(res.cost)}</b>. <a href="/solutions/{res.id}">View the solution</a>{view}.</p>
{robots}
<p>Your token (needed to withdraw it; it is shown only once):<br><code id="token">{e(res.token)}</code></p></div>"""
        return layout("Accepted", msg)
    viol = res.verdict.get("violations", [])
    items = "".join("<tr>" + (f'<td>{e(x.get("robot") or "cell")}</td>' if collab else "")
                    + f'<td><code>{e(x.get("constraint"))}</code></td><td>{e(x.get("goal", ""))}</td>'
                    f'<td class="num">{e(x.get("sample", ""))}</td><td>{e(x.get("message"))}</td></tr>' for x in viol)
    msg = f"""<div class="card banner-bad" id="result"><p class="bad">Invalid — the solution was not accepted
({len(viol)} violation{'s' if len(viol) != 1 else ''}).</p>
<p class="small">Benchmark <code>{e(res.benchmark_id)}</code></p>{robots}
<table><thead><tr>{"<th>Robot</th>" if collab else ""}<th>Constraint</th><th>Goal</th><th class="num">Sample</th>
<th>Message</th></tr></thead>
<tbody>{items}</tbody></table></div>"""
    return layout("Rejected", msg)


def error_page(status: int, message: str) -> str:
    body = f"""<h1>Error {status}</h1><div class="card banner-bad" id="result"><p class="bad">{e(message)}</p></div>
<p><a href="/">back to the benchmarks</a></p>"""
    return layout(f"Error {status}", body)


def api_docs(schema: dict) -> str:
    """``/api/docs``: the JSON API described from its OpenAPI schema, as a plain page of the site (no script, so the
    site's own Content-Security-Policy holds; the machine-readable schema is ``/api/openapi.json``)."""
    rows = []
    for path, ops in sorted((schema.get("paths") or {}).items()):
        for method, op in ops.items():
            if not isinstance(op, dict):
                continue
            params = ", ".join(f"{p.get('name')} ({p.get('in')}{', required' if p.get('required') else ''})"
                               for p in op.get("parameters") or [])
            answers = ", ".join(sorted((op.get("responses") or {}).keys()))
            text = op.get("description") or op.get("summary") or ""
            rows.append([f"<code>{e(method.upper())}</code>", f"<code>{e(path)}</code>", e(text.split("\n")[0]),
                         e(params), e(answers)])
    body = (f"<h1>{e(schema.get('info', {}).get('title', 'API'))}: JSON API</h1>"
            '<p>Every route of the JSON API. The machine-readable description is '
            '<a href="/api/openapi.json">/api/openapi.json</a> (OpenAPI); docs/website.md has the details and '
            'examples.</p>' + table(["Method", "Path", "What", "Parameters", "Answers"], rows))
    return layout("API", body)
