import pickle, sys
import numpy as np
a = pickle.load(open(sys.argv[1], "rb"))
b = pickle.load(open(sys.argv[2], "rb"))
assert len(a) == len(b), (len(a), len(b))
nfail = 0
def eq(x, y, path):
    global nfail
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        ok = isinstance(x, np.ndarray) and isinstance(y, np.ndarray) and x.dtype == y.dtype and np.array_equal(x, y)
        # bit identity (also -0.0 vs 0.0 and NaN): compare raw bytes
        ok = ok and x.tobytes() == y.tobytes()
        if not ok:
            nfail += 1
            if nfail < 20: print("DIFF", path, x, y)
        return
    if isinstance(x, (list, tuple)):
        if type(x) != type(y) or len(x) != len(y):
            nfail += 1
            if nfail < 20: print("DIFF len/type", path, x, y)
            return
        for i, (u, v) in enumerate(zip(x, y)):
            eq(u, v, path + [i])
        return
    if isinstance(x, dict):
        if set(x) != set(y):
            nfail += 1; print("DIFF keys", path, set(x) ^ set(y)); return
        for k in x:
            eq(x[k], y[k], path + [k])
        return
    if isinstance(x, float) and isinstance(y, float):
        ok = np.array(x).tobytes() == np.array(y).tobytes()
    else:
        ok = type(x) == type(y) and x == y
    if not ok:
        nfail += 1
        if nfail < 20: print("DIFF", path, repr(x), repr(y))
ncmp = 0
for i, (x, y) in enumerate(zip(a, b)):
    eq(x, y, [i])
print(f"{len(a)} robots compared, {nfail} differences")
sys.exit(1 if nfail else 0)
