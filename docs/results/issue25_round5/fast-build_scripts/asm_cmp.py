import sys, pickle, numpy as np
sys.path.insert(0, "/tmp/hb_old/src")
from robodesign.formats.module_io import load_module_set as LN
from robodesign_old.formats.module_io import load_module_set as LO
from robodesign.formats.assembly import Assembly as AN
from robodesign_old.formats.assembly import Assembly as AO
from robodesign.core.errors import AssemblyError as EN
from robodesign_old.core.errors import AssemblyError as EO
rng = np.random.default_rng(5)
n = bad = 0
for name in ("robodesign_arm", "/work/shared/cobra/modules/IMPROV"):
    mn, mo = LN(name), LO(name)
    ids = list(mn.ids) + ["nope"]
    orders = [o[2] for o in pickle.load(open("/tmp/hb/orders1000.pkl", "rb")) if o[1] == name]
    for o in orders:   # valid ones and mutated ones
        cands = [list(o)]
        for _ in range(5):
            m = list(o); j = rng.integers(len(m)); m[j] = ids[rng.integers(len(ids))]; cands.append(m)
            m = list(o); j = rng.integers(len(m)); del m[j]; cands.append(m)
            cands.append([ids[rng.integers(len(ids))] for _ in range(rng.integers(0, 8))])
        for c in cands:
            try: a = ("ok", AN._from_order(mn, c))
            except EN as e: a = ("err", str(e))
            try: b = ("ok", AO._from_order(mo, c))
            except EO as e: b = ("err", str(e))
            n += 1
            if a[0] != b[0] or (a[0] == "err" and a[1] != b[1]) or (a[0] == "ok" and (a[1].module_ids, a[1].connections, a[1].base) != (b[1].module_ids, b[1].connections, b[1].base)):
                bad += 1
                if bad < 5: print("DIFF", c, a, b)
print(n, "orders compared,", bad, "differences")
