import json, re, statistics as st
D = "/work/h-build/docs/results/issue25_round5/"
# ab separate
vals = {"base": {}, "new": {}}
for line in open(D + "fast-build_ab_separate_processes.txt"):
    m = re.match(r"(\S+) round \d+: (.*) n=", line)
    if not m: continue
    side = "base" if "hb_base" in m.group(1) else "new"
    for k, v in re.findall(r"(\w+)=([\d.]+)us", m.group(2)):
        vals[side].setdefault(k, []).append(float(v))
for k in vals["base"]:
    b, n = st.median(vals["base"][k]), st.median(vals["new"][k])
    print(f"separate {k:14s} base {b:7.1f} new {n:7.1f} ratio {b/n:.2f}  base {vals['base'][k]} new {vals['new'][k]}")
print(open(D + "fast-build_ab_paired.txt").read())
# profile evaluator
cur = None; rows = {"base": [], "new": []}
for line in open(D + "fast-build_profile_evaluator_ab.txt"):
    if line.startswith("## "): cur = "base" if "hb_base" in line else "new"; continue
    if line.startswith("| failed at ik"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        asm = float(cells[2].split()[0]); ik = float(cells[5].split()[0]); tot = float(cells[11].split()[0])
        rows[cur].append((asm, ik, tot))
for k, v in rows.items():
    print(f"evaluator {k}: assembly median {st.median(a for a,_,_ in v):.2f} ms {[a for a,_,_ in v]}, total median {st.median(t for _,_,t in v):.2f} {[t for _,_,t in v]}, assembly/ik median {st.median(a/i for a,i,_ in v):.2f}")
cur = None; g = {"base": [], "new": []}
for line in open(D + "fast-build_ga_ab.txt"):
    if line.startswith("## "): cur = "base" if "hb_base" in line else "new"; continue
    if line.startswith("{"): g[cur].append(json.loads(line))
for k, v in g.items():
    print(f"GA {k}: assembly s median {st.median(d['stage_seconds']['assembly'] for d in v)} {[d['stage_seconds']['assembly'] for d in v]} ask median {st.median(d['ask_seconds'] for d in v)} hashes {sorted(set(d['hash'] for d in v))}")
