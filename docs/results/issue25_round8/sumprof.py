import glob,re,statistics as st,sys
O=sys.argv[1]
for who in (sys.argv[2].split(",") if len(sys.argv) > 2 else ("base_s8","main")):
    rows={}
    for f in sorted(glob.glob(f"{O}/profile_r*_{who}.md")):
        sec=None
        for l in open(f):
            if l.startswith("### "): sec=l.split(",")[0][4:]
            if l.startswith("| feasible") or l.startswith("| failed at ik"):
                c=[x.strip() for x in l.strip().strip('|').split('|')]
                key=(sec,c[0]); vals=[]
                for x in c[2:]:
                    m=re.match(r"([0-9.]+)",x); vals.append(float(m.group(1)) if m else None)
                rows.setdefault(key,[]).append(vals)
    hdr=["assembly","base","reach","ik","static_torque","plan","timing","trajopt","check","total","cpu"]
    for k,v in rows.items():
        med=[st.median([r[i] for r in v if r[i] is not None]) if any(r[i] is not None for r in v) else None for i in range(len(hdr))]
        print(who,k,len(v),{h:m for h,m in zip(hdr,med) if m is not None}, "totals", [r[9] for r in v])
