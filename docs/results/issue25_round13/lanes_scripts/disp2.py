exec(open("/work/h-lanes/docs/results/issue25_round13/lanes_scripts/disp.py").read().split("ah = LN.Ahead")[0])
args = (40, lo, hi, ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, gm.N_inv, tkind, tvec, params)
N = 150
starts = np.where(np.isfinite(lo), lo, -3.14) + 0 * starts
starts = np.random.default_rng(0).uniform(-3, 3, (N, n)).clip(lo, hi)
def single():
    lanes = LN.new_lanes(n, 0)
    out = (lanes, np.zeros((N, n)), np.zeros((N, 4, 4)), np.full(N, LN.RUNNING, np.int64), np.zeros(N, np.int64))
    LN.lm_lanes(starts, 0, N, N, *args, *out)
def pattern():
    ah = LN.Ahead(args); w = 0; c = 0
    while w < N:
        r = ah.next_in_goal(starts, w, N)[0]; w = r + 1; c += 1
    return c
bargs = (40, lo, hi, ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, gm.N_inv, tkind, tvec, np.zeros(m), np.zeros((m, n)), np.zeros((4, 4)), params, np.zeros(n))
def scalar():
    w = 0
    while w < N:
        r = K.lm_batch(starts, w, N, *bargs)[0]; w = r + 1
def scalar1():
    K.lm_batch(starts, 0, N, *bargs)  # (stops at first hit) 
single(); pattern(); scalar()
print("hits", pattern())
for rnd in range(3):
    out = []
    for f in (scalar, single, pattern):
        t = time.process_time()
        for _ in range(50): f()
        out.append(f"{f.__name__} {(time.process_time() - t) / 50 * 1e3:.3f} ms")
    print(" | ".join(out), flush=True)
