#!/usr/bin/env python3
"""The structure classes of a 6R run's unclassified loops (docs/research/discovery-5r-6r.md,
"The generic 6R search's unclassified loops"). Python 3 standard library only.

  docs/research/generic6r_classes.py classes DB            # counts per class and rigid-residual band
  docs/research/generic6r_classes.py exact DB LOOPFARM JOB # the loops closing to round-off, a markdown table
  docs/research/generic6r_classes.py jacobian DB START LOOPFARM
      # singular values of the 6 x 6 closure Jacobian at the poses `loopfarm verify --theta0-deg T`
      # assembles on the loop's motion (T = 0, 30, ..., 330; verified, E_mean < 1e-15)
  docs/research/generic6r_classes.py jacobian-geometry A ALPHA_DEG D LOOPFARM
      # the same for a geometry given as comma lists, and the non-adjacent axis pairs whose
      # distance and angle stay the same (to 1e-9) in all those poses
  docs/research/generic6r_classes.py normal DB START LOOPFARM
      # a P9 loop: the direction n in which its cycle energy grows, over the ten parameters the
      # other eight conditions leave (kappa1, alpha1, alpha2, kappa2, alpha4, alpha5, a3, alpha3,
      # d1, d4): sqrt(E) of `loopfarm energy` with each moved by 1e-4, signs from pairs
  docs/research/generic6r_classes.py invariants DB
      # P9 loops closing to <= 1e-11: dyad invariants compared between the two dyads
  docs/research/generic6r_classes.py dyads SEED N LOOPFARM
      # N loops built from bennett_dyads' conditions (docs/guide/families.md), each checked with
      # `loopfarm verify --theta0-deg T`, T = 0, 5, ..., 355, until one verifies
  docs/research/generic6r_classes.py mobius DB START
      # the loop's motion followed with the rigid closure (Python, independent of loopfarm): the
      # joint pairs whose half-angle tangents are related by a Moebius map (a bilinear relation;
      # smallest singular value of [s_i s_j, s_i c_j, c_i s_j, c_i c_j] over the poses, s = sin(theta/2),
      # c = cos(theta/2)), and the pairs whose angle sum or difference stays constant
  docs/research/generic6r_classes.py mobius-geometry A ALPHA_DEG D
      # the same for a geometry given as comma lists (any n)
  docs/research/generic6r_classes.py mobius-all DB
      # the same over every unclassified loop closing to <= 1e-11, one line each
  docs/research/generic6r_classes.py cubic SEED ORDER LOOPFARM
      # a 6R from two factorisations of a random cubic motion polynomial (Hegedues, Schicho,
      # Schroecker 2013): C = (t - h1)(t - h2)(t - h3) = (t - k1)(t - k2)(t - k3), the k's in the
      # order ORDER of the norm factors (231 or 321); axes h1 h2 h3 k3 k2 k1; verified with loopfarm
  docs/research/generic6r_classes.py t7-normal DB START LOOPFARM
      # a T7 loop: the Hessian of the cycle energy over the nine parameters T7's visible conditions
      # leave (kappa1, alpha1..3, kappa2, alpha4..6, delta = d1 = +-d4); its two large eigenvalues'
      # vectors span the directions of the two unseen conditions
  docs/research/generic6r_classes.py t7-offsets DB
      # each T7 loop closing to <= 1e-11 with d1, d4 scaled by 0 and 2: does it still move (the
      # script's rigid closure, followed 80 steps with every pose closing to <= 1e-10)?
  docs/research/generic6r_classes.py t7-permutations DB LOOPFARM
      # each T7 loop with the twists of one triad permuted in all 6 ways (a = |sin alpha| / k of the
      # triad), with the loop's offsets (d4 = +-d1 exactly) and with d = 0: verified by `loopfarm verify`?
  docs/research/generic6r_classes.py t7-signs DB LOOPFARM
      # each T7 loop with one twist negated, or replaced by -180 deg - alpha, one triad's twists
      # negated, or all six (the mirror image), with the loop's offsets (as above) and with d = 0: verified?
  docs/research/generic6r_classes.py t7-triad-relations SEED N
      # N random triads with negative twists and N with positive ones at random joint angles: the
      # residuals of the two relations between their end axes (distance, angle, feet of the normal)
  docs/research/generic6r_classes.py t7-flip DB
      # each T7 loop with joint axes 1, 3, 5 reversed (every twist + 180 deg, d1, d3, d5 negated):
      # the other branch's pairing conditions with the signed ratio sin(alpha) / a, twists in (-180, 180]
  docs/research/generic6r_classes.py waldron SEED LOOPFARM
      # Waldron's hybrid: two Bennett loops ABCD, AEFG sharing the axis A, links AB, AE fused and
      # DA, GA fused, joint A removed: the 6R B C D G F E; verified with loopfarm
  docs/research/generic6r_classes.py b8-conditions DB
      # each B8 loop's labelling (reversal and shift; the B form turned into the A form) and the
      # residuals of B8's ten conditions: five visible, C1, C2, C3 (b8_conditions), the offset conditions L, Q, and
      # Q' (the same conic as Q; b8_offset_conditions)
  docs/research/generic6r_classes.py b8-count DB LOOPFARM
      # B8's number of conditions at each B8 loop by the reciprocal-wrench method: singular values of
      # the normal rows at 40 poses of its `loopfarm motion`, and whether the eight known are among them
  docs/research/generic6r_classes.py b8-build DB SEED N EPS LOOPFARM
      # N loops built from C1-C3 near the run's B8 loops, offsets solved by closure, verified with
      # loopfarm and counted as above; each verified one moved off C1, C2, C3 by EPS: does it close?
  docs/research/generic6r_classes.py b8-build10 SEED N EPS LOOPFARM     # e.g. SEED 2, N 25, EPS 1e-3
      # N random loops built from all ten of B8's conditions (the eight above and the offset conditions L, Q; offsets
      # from their parametric form, not by closure), verified with loopfarm (or: do they assemble at all?); near
      # misses with Q off (s scaled by 1 + EPS) and L off (d1, d2 moved by EPS L): do they move?
      # B8's loops (the first three b8-*): the unclassified loops closing to <= 1e-11 with B8's five
      # visible conditions in some labelling (b8_loops; in g6.sqlite the six of bond fingerprint
      # 6R/4 22 22 11 22 ...)
  docs/research/generic6r_classes.py near DB LOOPFARM FINGERPRINT
      # per unclassified loop whose bond fingerprint starts with FINGERPRINT (quoted), how near the trivial set:
      # the joint with the least fold residual max(|a_{k-1} - a_k|, |sin(alpha_{k-1} - alpha_k)|, |d_k|), the
      # nearest two joint axes (max(|sin angle|, distance)) over the poses of `loopfarm motion --csv`, the least
      # joint travel and the largest of the joints not turning fully (the rocking), the nearest family
  docs/research/generic6r_classes.py locked-bennett DB LOOPFARM FINGERPRINT
      # per loop of the class: its Bennett-ratio triad (three consecutive links of one ratio, d = 0 inside), the
      # two joints outside it (nearly locked) and their travel, Bennett's conditions on the 4R of the other four
      # axes over the poses of its motion; then the least parameter gap between members over relabellings
  docs/research/generic6r_classes.py triad-reorder DB LOOPFARM START FIRST
      # the loop at START with the links FIRST, FIRST+1, FIRST+2 (a Bennett-ratio triad) in each of the six
      # orders: does `loopfarm verify` find a circuit that moves, and its family and detail

Classes, tested on every shift and reversal of the canonical representation, each equality to 1e-6
(lengths in L, twists in degrees / 57.3; k_i = |sin alpha_i| / a_i, Bennett's ratio; a link
equals another when a and the twist agree up to sign and pi):
  pair  links 1 = 3, 4 = 6, 2 = 5, k1 = k2, k4 = k5, every d = 0 (bennett_pair's pattern)
  P9    link 3 = link 6, k1 = k2, k4 = k5, d2 = d5 = 0, |d1| = |d3|, |d4| = |d6|
  T7    k1 = k2 = k3, k4 = k5 = k6, d2 = d3 = d5 = d6 = 0, |d1| = |d4|
  B8    k2 = k3, k5 = k6, d3 = d6 = 0
"""
import collections, itertools, json, math, re, sqlite3, subprocess, sys

TOL = 1e-6
COLS = [f'a{i}' for i in range(1, 7)] + [f'alpha{i}_deg' for i in range(1, 7)] + [f'd{i}' for i in range(1, 7)]


def wrapd(x):
    return (x + 180) % 360 - 180


def same_link(a, al, i, k):
    if abs(a[i] - a[k]) > TOL:
        return False
    return min(abs(wrapd(al[i] - al[k])), abs(wrapd(al[i] + al[k])), abs(wrapd(al[i] - al[k] + 180)),
               abs(wrapd(al[i] + al[k] + 180))) < TOL * 57.3


def kappa(a, al, i):
    return abs(math.sin(math.radians(al[i]))) / a[i] if a[i] > 1e-12 else float('inf')


def same_kappa(a, al, i, k):
    return abs(kappa(a, al, i) - kappa(a, al, k)) < TOL * max(1.0, kappa(a, al, i))


def representations(a, al, d):
    for s in range(6):
        A = [a[(i + s) % 6] for i in range(6)]
        AL = [al[(i + s) % 6] for i in range(6)]
        D = [d[(i + s) % 6] for i in range(6)]
        yield A, AL, D
        # reversed: link i -> link 4 - i, joint i -> joint 5 - i (0-based; signs do not matter here)
        yield [A[(4 - i) % 6] for i in range(6)], [AL[(4 - i) % 6] for i in range(6)], [D[(5 - i) % 6] for i in range(6)]


def is_pair(A, AL, D):
    return (same_link(A, AL, 0, 2) and same_link(A, AL, 3, 5) and same_link(A, AL, 1, 4) and same_kappa(A, AL, 0, 1)
            and same_kappa(A, AL, 3, 4) and max(abs(x) for x in D) < TOL)


def is_p9(A, AL, D):
    return (same_link(A, AL, 2, 5) and same_kappa(A, AL, 0, 1) and same_kappa(A, AL, 3, 4) and abs(D[1]) < TOL
            and abs(D[4]) < TOL and abs(abs(D[0]) - abs(D[2])) < TOL and abs(abs(D[3]) - abs(D[5])) < TOL)


def is_t7(A, AL, D):
    return (same_kappa(A, AL, 0, 1) and same_kappa(A, AL, 1, 2) and same_kappa(A, AL, 3, 4) and same_kappa(A, AL, 4, 5)
            and all(abs(D[i]) < TOL for i in (1, 2, 4, 5)) and abs(abs(D[0]) - abs(D[3])) < TOL)


def is_b8(A, AL, D):
    return same_kappa(A, AL, 1, 2) and same_kappa(A, AL, 4, 5) and abs(D[2]) < TOL and abs(D[5]) < TOL


PATTERNS = [('pair', is_pair), ('P9', is_p9), ('T7', is_t7), ('B8', is_b8)]


def classify(a, al, d):
    for name, test in PATTERNS:
        if any(test(*w) for w in representations(a, al, d)):
            return name
    return 'none'


def rows(db, where=''):
    con = sqlite3.connect(db)
    q = (f"SELECT candidate_id, first_start, E_mean, local_dimension, rigid_residual, full_turn, {','.join(COLS)} "
         f"FROM candidates WHERE family = 'unclassified' {where} ORDER BY first_start")
    return con.execute(q).fetchall()


def band(r):
    if r[4] <= 1e-13 and r[2] <= 1e-24:
        return 'rigid <= 1e-13'
    return 'rigid <= 1e-11' if r[4] <= 1e-11 else 'rigid > 1e-11'


def cmd_classes(db):
    stats = collections.defaultdict(list)
    for r in rows(db):
        v = r[6:]
        stats[(classify(v[0:6], v[6:12], v[12:18]), band(r))].append(r)
    for key in sorted(stats):
        dims = collections.Counter(x[3] for x in stats[key])
        print(len(stats[key]), key, 'local dimensions', dict(sorted(dims.items())),
              'starts', [x[1] for x in stats[key]])


def travels(loopfarm, job, start):
    out = subprocess.run([loopfarm, 'start', job, '--index', str(start)], capture_output=True, text=True).stdout
    m = re.search(r'joint travel_deg\s+(.*)', out)
    return ', '.join(f"{float(x):.3g}" for x in m.group(1).split(',')) if m else '?'


def cmd_exact(db, loopfarm, job):
    print("| start | class | E_mean | local dim. | joint travels [deg] (`loopfarm start`) | a | alpha [deg] | d |")
    print("|---|---|---|---|---|---|---|---|")
    fmt = lambda xs: ' '.join(f"{x:.6g}" if abs(x) > 1e-9 else '0' for x in xs)
    for r in rows(db, 'AND rigid_residual <= 1e-13 AND E_mean <= 1e-24'):
        v = r[6:]
        print(f"| {r[1]} | {classify(v[0:6], v[6:12], v[12:18])} | {r[2]:.1e} | {r[3]} | {travels(loopfarm, job, r[1])} "
              f"| {fmt(v[0:6])} | {fmt(v[6:12])} | {fmt(v[12:18])} |")


# Rigid kinematics for the Jacobian: T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)
# (docs/design.md, "The loop and its closure").
def mat_mul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def dh(theta, d, a, alpha):
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]]


def screws(a, al, d, th):
    F = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    out = []
    for i in range(len(a)):
        w = [F[0][2], F[1][2], F[2][2]]
        p = [F[0][3], F[1][3], F[2][3]]
        out.append(w + [p[1] * w[2] - p[2] * w[1], p[2] * w[0] - p[0] * w[2], p[0] * w[1] - p[1] * w[0]])
        F = mat_mul(F, dh(th[i], d[i], a[i], al[i]))
    return out


def singular_values(S):
    """Ascending singular values of S (rows of 6), from the eigenvalues of its Gram matrix."""
    n = len(S)
    gram = [[sum(S[i][k] * S[j][k] for k in range(6)) for j in range(n)] for i in range(n)]
    return [math.sqrt(max(0.0, e)) for e in sym_eig(gram)[0]]


def axis_pair(S1, S2):
    """Distance and angle [deg] of two lines given as Pluecker screws (direction, moment)."""
    w1, m1, w2, m2 = S1[:3], S1[3:], S2[:3], S2[3:]
    cr = [w1[1] * w2[2] - w1[2] * w2[1], w1[2] * w2[0] - w1[0] * w2[2], w1[0] * w2[1] - w1[1] * w2[0]]
    s = math.sqrt(sum(x * x for x in cr))
    reciprocal = sum(x * y for x, y in zip(w1, m2)) + sum(x * y for x, y in zip(w2, m1))
    return (abs(reciprocal) / s if s > 1e-12 else float('nan')), math.degrees(math.atan2(s, sum(x * y for x, y in zip(w1, w2))))


def cmd_jacobian(db, start, loopfarm):
    con = sqlite3.connect(db)
    v = con.execute(f"SELECT {','.join('c.' + x for x in COLS)} FROM candidates c JOIN starts s USING (candidate_id) "
                    "WHERE s.start_index = ?", (int(start),)).fetchone()
    jacobian(list(v[0:6]), list(v[6:12]), list(v[12:18]), loopfarm)


def jacobian(a, al, d, loopfarm):
    pairs = []
    for t in range(0, 360, 30):
        out = subprocess.run([loopfarm, 'verify', '--a', ','.join(map(repr, a)), '--alpha-deg', ','.join(map(repr, al)),
                              '--d', ','.join(map(repr, d)), '--theta0-deg', str(t), '--json'], capture_output=True, text=True)
        j = json.loads(out.stdout)
        if not (j['verified'] and j['E_mean'] is not None and j['E_mean'] < 1e-15):
            continue
        S = screws(a, [math.radians(x) for x in al], d, [math.radians(x) for x in j['theta_deg']])
        sv = singular_values(S)
        print(f"theta0 {t:3d} deg ({j['family']}): smallest singular values", ' '.join(f"{x:.2g}" for x in sv[:3]))
        pairs.append({(i, k): axis_pair(S[i], S[k]) for i in range(6) for k in range(i + 2, 6) if (i, k) != (0, 5)})
    for key in (pairs[0] if pairs else {}):
        values = [p[key] for p in pairs]
        if max(v[0] for v in values) - min(v[0] for v in values) < 1e-9 and \
                max(v[1] for v in values) - min(v[1] for v in values) < 1e-7:
            print(f"axes {key[0] + 1} and {key[1] + 1}: distance {values[0][0]:.6f}, angle {values[0][1]:.3f} deg in all "
                  f"{len(values)} poses")


def p9_representation(a, al, d):
    for s in range(6):
        A = [a[(i + s) % 6] for i in range(6)]
        AL = [al[(i + s) % 6] for i in range(6)]
        D = [d[(i + s) % 6] for i in range(6)]
        if is_p9(A, AL, D):
            return A, AL, D
    return None


def energy(loopfarm, a, al, d):
    out = subprocess.run([loopfarm, 'energy', '--a', ','.join(map(repr, a)), '--alpha-deg=' + ','.join(map(repr, al)),
                          '--d=' + ','.join(map(repr, d)), '--json'], capture_output=True, text=True)
    return json.loads(out.stdout)['E_mean']


def cmd_normal(db, start, loopfarm, eps=1e-4):
    con = sqlite3.connect(db)
    v = con.execute(f"SELECT {','.join('c.' + x for x in COLS)} FROM candidates c JOIN starts s USING (candidate_id) "
                    "WHERE s.start_index = ?", (int(start),)).fetchone()
    A, AL, D = p9_representation(list(v[0:6]), list(v[6:12]), list(v[12:18]))
    R = math.radians
    p = {'kappa1': math.sin(R(AL[0])) / A[0], 'alpha1': R(AL[0]), 'alpha2': R(AL[1]), 'kappa2': math.sin(R(AL[3])) / A[3],
         'alpha4': R(AL[3]), 'alpha5': R(AL[4]), 'a3': A[2], 'alpha3': R(AL[2]), 'd1': D[0], 'd4': D[3]}

    def E(q):
        a = [math.sin(q['alpha1']) / q['kappa1'], math.sin(q['alpha2']) / q['kappa1'], q['a3'],
             math.sin(q['alpha4']) / q['kappa2'], math.sin(q['alpha5']) / q['kappa2'], q['a3']]
        al = [math.degrees(q[k]) for k in ('alpha1', 'alpha2', 'alpha3', 'alpha4', 'alpha5', 'alpha3')]
        return energy(loopfarm, a, al, [q['d1'], 0.0, q['d1'], q['d4'], 0.0, q['d4']])

    print('E at the loop', f"{E(p):.2g}")
    size = {}
    for k in p:
        q = dict(p)
        q[k] += eps
        size[k] = math.sqrt(max(E(q), 0.0)) / eps
    print('sqrt(E) / 1e-4 per parameter:', ' '.join(f"{k} {x:.2g}" for k, x in size.items()))
    ref = max(size, key=size.get)
    n = {}
    for k in p:
        if k == ref or size[k] < 1e-3 * size[ref]:
            n[k] = size[k]
            continue
        q = dict(p)
        q[ref] += eps
        q[k] += eps
        both = math.sqrt(E(q)) / eps
        n[k] = size[k] if abs(both - (size[ref] + size[k])) < abs(both - abs(size[ref] - size[k])) else -size[k]
    norm = math.sqrt(sum(x * x for x in n.values()))
    print('n:', ' '.join(f"{k} {x / norm:+.4g}" for k, x in n.items()))


def cmd_invariants(db):
    R = math.radians
    sums = []
    for r in rows(db, 'AND rigid_residual <= 1e-11'):
        w = p9_representation(list(r[6:12]), list(r[12:18]), list(r[18:24]))
        if not w:
            continue
        A, AL, D = w

        def dyad(i):
            k, x, y = math.sin(R(AL[i])) / A[i], R(AL[i]), R(AL[i + 1])
            return {'(cos alpha + cos beta) / kappa': (math.cos(x) + math.cos(y)) / k, 'kappa': k,
                    'sin((b+a)/2) / sin((b-a)/2)': math.sin((y + x) / 2) / math.sin((y - x) / 2),
                    'cos((b+a)/2) / cos((b-a)/2)': math.cos((y + x) / 2) / math.cos((y - x) / 2)}
        sums.append((dyad(0), dyad(3)))
    print(len(sums), 'P9 loops closing to <= 1e-11')
    for key in sums[0][0]:
        rel = sorted(abs(u[key] - v[key]) / max(1e-12, abs(u[key])) for u, v in sums)
        print(f"{key}: relative difference between the dyads, median {rel[len(rel) // 2]:.2g}, largest {rel[-1]:.2g}")


def dyads_member(rng):
    while True:
        k1, k2 = -rng.uniform(0.4, 1.5), -rng.uniform(0.4, 1.5)
        t1, t2, t4 = (-rng.uniform(0.3, math.pi - 0.3) for _ in range(3))
        c5 = (math.cos(t1) + math.cos(t2)) / k1 * k2 - math.cos(t4)
        if abs(c5) > 0.95:
            continue
        t5 = -math.acos(c5)
        a = [math.sin(t1) / k1, math.sin(t2) / k1, rng.uniform(0.5, 1.5), math.sin(t4) / k2, math.sin(t5) / k2]
        a.append(a[2])
        if min(a) < 0.2 or max(a) > 3:
            continue
        gamma = -rng.uniform(0.3, math.pi - 0.3)
        e, f = rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3)
        return a, [math.degrees(x) for x in (t1, t2, gamma, t4, t5, gamma)], [e, 0.0, e, f, 0.0, f]


def cmd_dyads(seed, count, loopfarm):
    import random
    rng = random.Random(int(seed))
    moved = 0
    for i in range(int(count)):
        a, al, d = dyads_member(rng)
        for t in range(0, 360, 5):
            out = subprocess.run([loopfarm, 'verify', '--a', ','.join(map(repr, a)), '--alpha-deg=' + ','.join(map(repr, al)),
                                  '--d=' + ','.join(map(repr, d)), '--theta0-deg', str(t), '--json'],
                                 capture_output=True, text=True)
            j = json.loads(out.stdout)
            if j['verified'] and j['rigid_residual'] < 1e-12:
                moved += 1
                lo, hi = j['input_range_deg']
                print(f"{i}: verified from theta0 {t} deg, rigid residual {j['rigid_residual']:.1g}, input "
                      f"{'full turn' if j['full_turn'] else f'{hi - lo:.1f} deg'}, E_mean {j['E_mean']:.2g}, "
                      f"local dimension {j['local_dimension']}, {j['family']}")
                break
        else:
            print(f"{i}: no verified assembly at theta0 = 0, 5, ..., 355 deg")
    print(moved, 'of', count, 'moved')


# ---- Motions followed with the rigid closure, and constructions from the literature ----
def closure_residual(a, al, d, th):
    F = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    for i in range(len(a)):
        F = mat_mul(F, dh(th[i], d[i], a[i], al[i]))
    return [F[i][j] - (1.0 if i == j else 0.0) for i in range(3) for j in range(4)]


def solve(A, b):
    n = len(b)
    M = [row[:] + [b[i]] for i, row in enumerate(A)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(M[r][c]))
        M[c], M[p] = M[p], M[c]
        for r in range(n):
            if r != c and M[c][c] != 0:
                f = M[r][c] / M[c][c]
                for k in range(c, n + 1):
                    M[r][k] -= f * M[c][k]
    return [M[i][n] / M[i][i] if M[i][i] != 0 else 0.0 for i in range(n)]


def jac(a, al, d, th, free):
    r = closure_residual(a, al, d, th)
    J = []
    for k in free:
        t2 = list(th)
        t2[k] += 1e-7
        J.append([(x - y) / 1e-7 for x, y in zip(closure_residual(a, al, d, t2), r)])
    return r, J


def lm_close(a, al, d, th, free, iters=100, lam=1e-3):
    th = list(th)
    for _ in range(iters):
        r, J = jac(a, al, d, th, free)
        if sum(x * x for x in r) < 1e-28:
            break
        A = [[sum(u * v for u, v in zip(J[i], J[j])) + (lam if i == j else 0) for j in range(len(free))]
             for i in range(len(free))]
        step = solve(A, [-sum(u * v for u, v in zip(J[i], r)) for i in range(len(free))])
        for i, k in enumerate(free):
            th[k] += step[i]
    return th, math.sqrt(sum(x * x for x in closure_residual(a, al, d, th)))


def sym_eig(G):
    """Jacobi: eigenvalues ascending and their eigenvectors."""
    n = len(G)
    A = [row[:] for row in G]
    V = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    for _ in range(100):
        if sum(A[i][j] ** 2 for i in range(n) for j in range(n) if i != j) < 1e-40:
            break
        for p in range(n):
            for q in range(p + 1, n):
                if abs(A[p][q]) < 1e-300:
                    continue
                t = 0.5 * math.atan2(2 * A[p][q], A[q][q] - A[p][p])
                c, s = math.cos(t), math.sin(t)
                for M in (A, V):
                    for k in range(n):
                        M[k][p], M[k][q] = c * M[k][p] - s * M[k][q], s * M[k][p] + c * M[k][q]
                for k in range(n):
                    A[p][k], A[q][k] = c * A[p][k] - s * A[q][k], s * A[p][k] + c * A[q][k]
    order = sorted(range(n), key=lambda i: A[i][i])
    return [A[i][i] for i in order], [[V[k][i] for k in range(n)] for i in order]


def assemble(a, al, d, seed=0, tries=300):
    import random
    rng = random.Random(seed)
    for _ in range(tries):
        th, res = lm_close(a, al, d, [rng.uniform(-math.pi, math.pi) for _ in a], list(range(len(a))))
        if res < 1e-11:
            return th
    return None


def trace(a, al, d, th, steps=120, h=0.05):
    """Arc-length continuation along the closure's null direction (one degree of freedom)."""
    poses, prev = [list(th)], None
    for _ in range(steps):
        r, J = jac(a, al, d, th, range(len(a)))
        v = sym_eig([[sum(u * w for u, w in zip(J[i], J[j])) for j in range(len(a))] for i in range(len(a))])[1][0]
        if prev is not None and sum(x * y for x, y in zip(v, prev)) < 0:
            v = [-x for x in v]
        k = max(range(len(a)), key=lambda i: abs(v[i]))
        th2, res = lm_close(a, al, d, [x + h * y for x, y in zip(th, v)], [i for i in range(len(a)) if i != k], 50, 1e-8)
        if res > 1e-10:
            break
        poses.append(th2)
        prev, th = v, th2
    return poses


def mobius_sv(poses, i, j):
    rows = [[math.sin(p[i] / 2) * math.sin(p[j] / 2), math.sin(p[i] / 2) * math.cos(p[j] / 2),
             math.cos(p[i] / 2) * math.sin(p[j] / 2), math.cos(p[i] / 2) * math.cos(p[j] / 2)] for p in poses]
    G = [[sum(r[u] * r[v] for r in rows) / len(rows) for v in range(4)] for u in range(4)]
    return math.sqrt(max(sym_eig(G)[0][0], 0.0))


def mobius_summary(a, al_deg, d, steps=120):
    al = [math.radians(x) for x in al_deg]
    th = assemble(a, al, d)
    if th is None:
        return None
    poses = trace(a, al, d, th, steps)
    n = len(a)
    travel = [max(abs(math.remainder(p[k] - poses[0][k], 2 * math.pi)) for p in poses) for k in range(n)]
    if len(poses) < 20:
        return {'poses': len(poses)}
    moving = [k for k in range(n) if travel[k] > math.radians(1)]  # a joint that hardly turns relates to any
    sv = {(i, j): mobius_sv(poses, i, j) for i in moving for j in moving if i < j}
    const = []
    for (i, j) in sv:
        for sg, name in ((1, '-'), (-1, '+')):
            v = [math.remainder(p[i] - sg * p[j] - (poses[0][i] - sg * poses[0][j]), 2 * math.pi) for p in poses]
            if max(abs(x) for x in v) < 1e-7:
                const.append(f"{i + 1}{name}{j + 1}")
    related = [k for k, v in sv.items() if v < 1e-7]
    return {'poses': len(poses), 'still': [k + 1 for k in range(n) if k not in moving], 'pairs': len(sv),
            'related': ' '.join(f"{i + 1}-{j + 1}" for i, j in related),
            'largest_related': max([sv[k] for k in related], default=0.0),
            'smallest_other': min([v for k, v in sv.items() if k not in related], default=float('nan')), 'const': const}


def print_mobius(label, m):
    if m is None:
        print(label, 'no assembly found')
        return
    if 'related' not in m:
        print(label, f"the motion was not followed ({m['poses']} poses)")
        return
    still = f"joints {m['still']} turn < 1 deg over the poses and are left out; " if m['still'] else ''
    print(f"{label}: {m['poses']} poses; {still}Moebius-related pairs ({len(m['related'].split())} of {m['pairs']}): "
          f"{m['related'] or '-'} "
          f"(their singular value <= {m['largest_related']:.1g}, the others' >= {m['smallest_other']:.1g}); "
          f"constant angle sum or difference: {' '.join(m['const']) or '-'}")


def cmd_mobius(db, start):
    con = sqlite3.connect(f'file:{db}?mode=ro', uri=True)
    v = con.execute(f"SELECT {','.join('c.' + x for x in COLS)} FROM candidates c JOIN starts s USING (candidate_id) "
                    "WHERE s.start_index = ?", (int(start),)).fetchone()
    print_mobius(f"start {start}", mobius_summary(list(v[0:6]), list(v[6:12]), list(v[12:18])))


def cmd_mobius_all(db):
    for r in rows(db, 'AND rigid_residual <= 1e-11'):
        v = r[6:]
        print_mobius(f"start {r[1]} ({classify(v[0:6], v[6:12], v[12:18])}, local dim. {r[3]})",
                     mobius_summary(list(v[0:6]), list(v[6:12]), list(v[12:18])))


# Dual quaternions as pairs of quaternions (primal, dual); a rotation factor t - h has h = (h0 + v, w), v.w = 0.
def qmul(a, b):
    return (a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3], a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1], a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0])


def dq_mul(x, y):
    return (qmul(x[0], y[0]), tuple(u + v for u, v in zip(qmul(x[0], y[1]), qmul(x[1], y[0]))))


def dq_add(x, y, s=1.0):
    return tuple(tuple(u + s * v for u, v in zip(x[k], y[k])) for k in range(2))


def dq_inv(x):
    n = sum(u * u for u in x[0])
    pi = (x[0][0] / n, -x[0][1] / n, -x[0][2] / n, -x[0][3] / n)
    return (pi, tuple(-u for u in qmul(qmul(pi, x[1]), pi)))


ZERO, ONE = ((0.0,) * 4, (0.0,) * 4), ((1.0, 0.0, 0.0, 0.0), (0.0,) * 4)


def poly_mul(P, Q):
    R = [ZERO] * (len(P) + len(Q) - 1)
    for i, p in enumerate(P):
        for j, q in enumerate(Q):
            R[i + j] = dq_add(R[i + j], dq_mul(p, q))
    return R


def right_factor(P, quad):
    """The right factor t - k of the monic motion polynomial P whose norm is t^2 + b t + c; P / (t - k)."""
    b, c = quad
    R = list(P)
    for i in range(len(R) - 1, 1, -1):
        lead, R[i] = R[i], ZERO
        R[i - 1], R[i - 2] = dq_add(R[i - 1], lead, -b), dq_add(R[i - 2], lead, -c)
    k = dq_add(ZERO, dq_mul(dq_inv(R[1]), R[0]), -1.0)
    n = len(P) - 1
    Q = [ZERO] * n
    Q[n - 1] = P[n]
    for i in range(n - 1, 0, -1):
        Q[i - 1] = dq_add(P[i], dq_mul(Q[i], k))
    return k, Q


def random_rotation(rng):
    v, w = [rng.gauss(0, 1) for _ in range(3)], [rng.gauss(0, 1) for _ in range(3)]
    f = sum(x * y for x, y in zip(v, w)) / sum(x * x for x in v)
    return ((rng.uniform(-1.5, 1.5), *v), (0.0, *[x - f * y for x, y in zip(w, v)]))


def cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def dot(u, v):
    return sum(x * y for x, y in zip(u, v))


def line_of(h):
    v, w = list(h[0][1:]), list(h[1][1:])
    n2 = dot(v, v)
    return [x / n2 for x in cross(v, w)], [x / math.sqrt(n2) for x in v]


def dh_from_lines(lines):
    """DH parameters (this project's convention, a_i >= 0, lengths scaled to L) and the pose of n lines."""
    n = len(lines)
    a, al, d, xs, s_next, s_prev = [0.0] * n, [0.0] * n, [0.0] * n, [None] * n, [0.0] * n, [0.0] * n
    for i in range(n):
        (q1, u1), (q2, u2) = lines[i], lines[(i + 1) % n]
        c = cross(u1, u2)
        x = [y / math.sqrt(dot(c, c)) for y in c]
        w0 = [p - q for p, q in zip(q1, q2)]
        b, e1, e2 = dot(u1, u2), dot(u1, w0), dot(u2, w0)
        s1, s2 = (b * e2 - e1) / (1 - b * b), (e2 - b * e1) / (1 - b * b)
        gap = [q + s2 * u - p - s1 * v for p, v, q, u in zip(q1, u1, q2, u2)]
        if dot(gap, x) < 0:
            x = [-y for y in x]
        a[i], al[i], xs[i] = dot(gap, x), math.degrees(math.atan2(dot(x, cross(u1, u2)), dot(u1, u2))), x
        s_next[i], s_prev[(i + 1) % n] = s1, s2
    th = [math.atan2(dot(lines[i][1], cross(xs[i - 1], xs[i])), dot(xs[i - 1], xs[i])) for i in range(n)]
    d = [s_next[i] - s_prev[i] for i in range(n)]
    L = math.sqrt(sum(x * x for x in a + d) / n)
    return [x / L for x in a], al, [x / L for x in d], th


def cubic_loop(seed, order):
    import random
    rng = random.Random(int(seed))
    hs = [random_rotation(rng) for _ in range(3)]
    norms = [(-2 * h[0][0], sum(x * x for x in h[0])) for h in hs]
    P = poly_mul(poly_mul([dq_add(ZERO, hs[0], -1), ONE], [dq_add(ZERO, hs[1], -1), ONE]), [dq_add(ZERO, hs[2], -1), ONE])
    ks = [None] * 3
    for pos in (2, 1):
        ks[pos], P = right_factor(P, norms[int(order[pos]) - 1])
    ks[0] = dq_add(ZERO, P[0], -1)
    return dh_from_lines([line_of(h) for h in hs] + [line_of(k) for k in reversed(ks)])


def waldron_loop(seed):
    import random
    rng = random.Random(int(seed))

    def bennett(k):
        x, y = rng.uniform(0.3, 2.8), rng.uniform(0.3, 2.8)
        A, AL = [math.sin(x) / k, math.sin(y) / k] * 2, [x, y] * 2
        while True:
            th, res = lm_close(A, AL, [0.0] * 4, [rng.uniform(-math.pi, math.pi) for _ in range(4)], [1, 2, 3])
            if res < 1e-13:
                break
        F, axes = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)], []
        for i in range(4):
            axes.append(F)
            F = mat_mul(F, dh(th[i], 0.0, A[i], AL[i]))
        return axes
    loop1, loop2 = bennett(rng.uniform(0.5, 1.5)), bennett(rng.uniform(0.5, 1.5))
    place = dh(rng.uniform(-3, 3), rng.uniform(-0.5, 0.5), 0.0, 0.0)  # loop 2 turned and slid along the axis A
    loop2 = [mat_mul(place, F) for F in loop2]
    line = lambda F: ([F[0][3], F[1][3], F[2][3]], [F[0][2], F[1][2], F[2][2]])
    return dh_from_lines([line(loop1[1]), line(loop1[2]), line(loop1[3]), line(loop2[3]), line(loop2[2]), line(loop2[1])])


def report_built(label, a, al, d, th, loopfarm):
    print(f"{label}: closure at the built pose {max(abs(x) for x in closure_residual(a, [math.radians(x) for x in al], d, th)):.1g}")
    print('  --a', ','.join(map(repr, a)), '--alpha-deg=' + ','.join(map(repr, al)), '--d=' + ','.join(map(repr, d)))
    k = [abs(math.sin(math.radians(y))) / x for x, y in zip(a, al)]
    print('  |sin alpha| / a:', ' '.join(f"{x:.6f}" for x in k), '; d:', ' '.join(f"{x:.3g}" for x in d))
    out = subprocess.run([loopfarm, 'verify', '--a', ','.join(map(repr, a)), '--alpha-deg=' + ','.join(map(repr, al)),
                          '--d=' + ','.join(map(repr, d)), '--json'], capture_output=True, text=True)
    j = json.loads(out.stdout)
    print(f"  loopfarm verify: verified {j['verified']}, {j['family']}, rigid residual {j['rigid_residual']:.1g}, "
          f"E_mean {j['E_mean']:.2g}, full turn {j['full_turn']}, local dimension {j['local_dimension']}")
    print_mobius('  motion', mobius_summary(a, al, d, 100))


def t7_representation(a, al, d):
    for s in range(6):  # a cyclic shift is a representation of the same loop (no reversal: signs would change)
        A, AL, D = ([v[(i + s) % 6] for i in range(6)] for v in (a, al, d))
        if is_t7(A, AL, D):
            return A, AL, D
    return None


def t7_geometry(p, sign):
    k1, x1, x2, x3, k2, x4, x5, x6, delta = p
    return ([math.sin(x1) / k1, math.sin(x2) / k1, math.sin(x3) / k1, math.sin(x4) / k2, math.sin(x5) / k2, math.sin(x6) / k2],
            [math.degrees(v) for v in (x1, x2, x3, x4, x5, x6)], [delta, 0.0, 0.0, sign * delta, 0.0, 0.0])


def cmd_t7_normal(db, start, loopfarm, eps=1e-5):
    """Hessian of the cycle energy (input range 20 deg from a pose on the motion) over the nine parameters that
    T7's visible conditions leave: kappa1, alpha1..3, kappa2, alpha4..6, delta (d1 = delta, d4 = +-delta)."""
    con = sqlite3.connect(f'file:{db}?mode=ro', uri=True)
    v = con.execute(f"SELECT {','.join('c.' + x for x in COLS)} FROM candidates c JOIN starts s USING (candidate_id) "
                    "WHERE s.start_index = ?", (int(start),)).fetchone()
    A, AL, D = t7_representation(list(v[0:6]), list(v[6:12]), list(v[12:18]))
    R = [math.radians(x) for x in AL]
    p = [math.sin(R[0]) / A[0], R[0], R[1], R[2], math.sin(R[3]) / A[3], R[3], R[4], R[5], D[0]]
    sign = 1.0 if abs(D[3] - D[0]) < 1e-6 else -1.0

    def E(q, th):
        a, al, d = t7_geometry(q, sign)
        out = subprocess.run([loopfarm, 'energy', '--a', ','.join(map(repr, a)), '--alpha-deg=' + ','.join(map(repr, al)),
                              '--d=' + ','.join(map(repr, d)), '--theta-deg=' + ','.join(repr(math.degrees(t)) for t in th),
                              '--range-deg', '20', '--json'], capture_output=True, text=True)
        return json.loads(out.stdout)['E_mean']
    a, al, d = t7_geometry(p, sign)
    for seed in range(40):  # a pose on the loop's motion (another assembly mode has a cycle energy > 0)
        th = assemble(a, [math.radians(x) for x in al], d, seed)
        if th is not None and E(p, th) < 1e-20:
            break
    print(f"start {start}: E at the loop {E(p, th):.1g} (d4 = {'+' if sign > 0 else '-'}d1)")
    n = len(p)
    Ei = []
    for i in range(n):
        q = list(p)
        q[i] += eps
        Ei.append(E(q, th))
    H = [[0.0] * n for _ in range(n)]
    for i in range(n):
        H[i][i] = 2 * Ei[i] / eps ** 2
        for j in range(i + 1, n):
            q = list(p)
            q[i] += eps
            q[j] += eps
            H[i][j] = H[j][i] = (E(q, th) - Ei[i] - Ei[j]) / eps ** 2
    ev, V = sym_eig(H)
    print('  Hessian eigenvalues:', ' '.join(f"{x:.2g}" for x in ev))
    names = ['kappa1', 'alpha1', 'alpha2', 'alpha3', 'kappa2', 'alpha4', 'alpha5', 'alpha6', 'delta']
    for k in (-1, -2):
        print('  normal:', ' '.join(f"{nm} {c:+.4f}" for nm, c in zip(names, V[k])))


def cmd_t7_offsets(db):
    """Each T7 loop with its offsets d1, d4 scaled by f = 0 and 2: assembled (the script's rigid closure, up to 5 x 100
    random guesses) and its motion followed (80 steps; every pose closes to <= 1e-10)?"""
    for r in rows(db, 'AND rigid_residual <= 1e-11'):
        w = t7_representation(list(r[6:12]), list(r[12:18]), list(r[18:24]))
        if not w:
            continue
        A, AL, D = w
        al = [math.radians(x) for x in AL]
        out = []
        for f in (0.0, 2.0):
            d = [x * f for x in D]
            best = None
            for seed in range(5):
                th = assemble(A, al, d, seed, 100)
                if th is None:
                    continue
                poses = trace(A, al, d, th, 80)
                travel = max(abs(math.remainder(p[k] - poses[0][k], 2 * math.pi)) for p in poses for k in range(6))
                if best is None or travel > best[1]:
                    best = (len(poses), travel)
                if len(poses) > 20:
                    break
            out.append(f"d x {f}: " + (f"{best[0]} poses, largest joint travel {math.degrees(best[1]):.1f} deg" if best
                                       else 'no assembly'))
        print(f"start {r[1]}:", '; '.join(out), flush=True)


def t7_loops(db):
    """The T7 loops of a run closing to <= 1e-11, as t7-offsets takes them: start, a, alpha [deg], d in the labelling
    where T7's visible conditions hold (links 1-3 one Bennett ratio, links 4-6 another, d1 and d4 the only offsets)."""
    for r in rows(db, 'AND rigid_residual <= 1e-11'):
        w = t7_representation(list(r[6:12]), list(r[12:18]), list(r[18:24]))
        if w:
            yield (r[1], *w)


def t7_branch(d):
    return '+' if abs(d[3] - d[0]) < 1e-6 else '-'


def verify(loopfarm, a, al, d):
    out = subprocess.run([loopfarm, 'verify', '--a', ','.join(map(repr, a)), '--alpha-deg=' + ','.join(map(repr, al)),
                          '--d=' + ','.join(map(repr, d)), '--json'], capture_output=True, text=True)
    return json.loads(out.stdout)


def t7_offsets(d):
    """The offsets in T7's form: d1 = delta, d4 = +-delta exactly, the others 0. A search's loop has the others and
    |d4| - |d1| at 1e-12 or so, enough for `loopfarm verify` not to call it verified as given: start 1164 (one of the
    8 T7 loops docs/guide/families.md lists) closes to 2.4e-12 with its stored offsets, and verify's polish moves it
    by 3.6e-12 (more than round-off, 1e-12) onto a loop that moves."""
    return [d[0], 0.0, 0.0, d[0] if t7_branch(d) == '+' else -d[0], 0.0, 0.0]


def verdict(loopfarm, a, al, d, tally, key):
    """`loopfarm verify` (every circuit over the whole turn): 'Y' verified, 'p' not, but its polish onto the motion the
    geometry approximates (moved by more than round-off) verified, 'n' neither; counted in tally[key] and tally[key, 'p'],
    the largest such polish's displacement in tally[key, 'moved']."""
    j = verify(loopfarm, a, al, d)
    if j['verified']:
        tally[key] += 1
        return 'Y'
    if (j.get('polish') or {}).get('verified'):
        tally[key, 'p'] += 1
        tally[key, 'moved'] = max(tally[key, 'moved'], j['polish']['displacement'])
        return 'p'
    return 'n'


def tally_line(tally, key, n):
    near = f" (and {tally[key, 'p']} more once polished onto a motion, moved by <= {tally[key, 'moved']:.1g})" \
        if tally[key, 'p'] else ''
    return f"{tally[key]} of {n} verified{near}"


def cmd_t7_permutations(db, loopfarm):
    """Each T7 loop with the twists of links 1-3, or of links 4-6, permuted in all 6 ways (the identity among them),
    each link's length recomputed from its triad's Bennett ratio, a = |sin alpha| / k: does `loopfarm verify` (every
    circuit over the whole turn) verify it? With the loop's offsets in T7's form (t7_offsets) and with every offset 0."""
    import itertools
    tally, n = collections.Counter(), 0
    for start, A, AL, D in t7_loops(db):
        n += 1
        k = (kappa(A, AL, 0), kappa(A, AL, 3))
        out = []
        for tri in (0, 1):
            for name, d in (('its offsets', t7_offsets(D)), ('d = 0', [0.0] * 6)):
                marks = ''
                for perm in itertools.permutations(range(3)):
                    al = list(AL)
                    for i, q in enumerate(perm):
                        al[3 * tri + i] = AL[3 * tri + q]
                    a = [abs(math.sin(math.radians(x))) / k[i // 3] for i, x in enumerate(al)]
                    marks += verdict(loopfarm, a, al, d, tally, (tri, name))
                out.append(f"links {3 * tri + 1}-{3 * tri + 3}, {name}: {marks}")
        print(f"start {start} (d4 = {t7_branch(D)}d1):", '; '.join(out), flush=True)
    for tri in (0, 1):
        for name, label in (('its offsets', "the loops' offsets"), ('d = 0', 'd = 0')):
            print(f"twists of links {3 * tri + 1}-{3 * tri + 3} permuted, {label}: {tally_line(tally, (tri, name), 6 * n)}")


def cmd_t7_signs(db, loopfarm):
    """Each T7 loop with mixed twist signs: one twist negated (6 ways), one twist replaced by -180 deg - alpha (its cosine
    negated, 6 ways), the twists of links 1-3 or of links 4-6 negated; and all six negated with the offsets (the mirror
    image). The lengths stay (|sin alpha| does not change). Verified by `loopfarm verify` (every circuit over the whole
    turn)? With the loop's offsets in T7's form (t7_offsets) and with every offset 0."""
    def changed(al, i, f):
        return [f(x) if j == i else x for j, x in enumerate(al)]
    kinds = [('one twist negated', 'alpha_i -> -alpha_i',
              [lambda al, d, i=i: (changed(al, i, lambda x: -x), d) for i in range(6)]),
             ('one twist replaced by -180 deg - alpha', 'alpha_i -> -180 - alpha_i',
              [lambda al, d, i=i: (changed(al, i, lambda x: -180 - x), d) for i in range(6)]),
             ('the twists of links 1-3 negated', 'links 1-3', [lambda al, d: ([-x for x in al[:3]] + al[3:], d)]),
             ('the twists of links 4-6 negated', 'links 4-6', [lambda al, d: (al[:3] + [-x for x in al[3:]], d)]),
             ('all six twists and the offsets negated (the mirror image)', 'mirror',
              [lambda al, d: ([-x for x in al], [-x for x in d])])]
    tally, n = collections.Counter(), 0
    for start, A, AL, D in t7_loops(db):
        n += 1
        out = []
        for name, short, variants in kinds:
            marks = [''.join(verdict(loopfarm, A, *f(list(AL), list(d0)), tally, (name, dname)) for f in variants)
                     for dname, d0 in (('its offsets', t7_offsets(D)), ('d = 0', [0.0] * 6))]
            out.append(f"{short} {marks[0]} / {marks[1]}")
        print(f"start {start} (verified? with its offsets / with d = 0):", '; '.join(out), flush=True)
    for name, short, variants in kinds:
        print(f"{name}: with the loops' offsets {tally_line(tally, (name, 'its offsets'), n * len(variants))}, "
              f"with d = 0 {tally_line(tally, (name, 'd = 0'), n * len(variants))}")


def triad_end_axes(a, al, th):
    """A triad (three links, no offsets) at joint angles th: the distance D of its end axes (axes 1 and 4; signed,
    positive along z1 x z4), their angle beta, and the feet of their common normal: s1 on axis 1 from link 1's foot,
    s4 on axis 4 from link 3's foot."""
    F = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    for i in range(3):
        F = mat_mul(F, dh(th[i], 0.0, a[i], al[i]))
    v, p = [F[0][2], F[1][2], F[2][2]], [F[0][3], F[1][3], F[2][3]]
    n = cross([0.0, 0.0, 1.0], v)
    c, pv = v[2], dot(p, v)
    s1, s4 = (p[2] - c * pv) / (1 - c * c), (c * p[2] - pv) / (1 - c * c)
    w = [p[i] + s4 * v[i] - (s1 if i == 2 else 0.0) for i in range(3)]
    return math.copysign(math.sqrt(dot(w, w)), dot(w, n)), math.atan2(math.sqrt(dot(n, n)), c), s1, s4


def triad_relations(k, al, D, beta, s1, s4):
    """The residuals of the two relations of a triad of Bennett ratio k (C = cos(beta/2), S = sin(beta/2)):
    (-)  C^2 (s1 - s4)^2 + (S D - lam_m C)^2 = kap_m, lam_m = (1 + sum cos alpha) / k, kap_m = 16 prod cos^2(alpha/2) / k^2
    (+)  S^2 (s1 + s4)^2 + (C D - lam_p S)^2 = kap_p, lam_p = (1 - sum cos alpha) / k, kap_p = 16 prod sin^2(alpha/2) / k^2"""
    C, S = math.cos(beta / 2), math.sin(beta / 2)
    lm, lp = (1 + sum(math.cos(x) for x in al)) / k, (1 - sum(math.cos(x) for x in al)) / k
    km = 16 * math.prod(math.cos(x / 2) ** 2 for x in al) / k ** 2
    kp = 16 * math.prod(math.sin(x / 2) ** 2 for x in al) / k ** 2
    return (C * C * (s1 - s4) ** 2 + (S * D - lm * C) ** 2 - km, S * S * (s1 + s4) ** 2 + (C * D - lp * S) ** 2 - kp)


def cmd_t7_triad_relations(seed, count):
    """N random triads with negative twists, then N with positive twists (k in [0.3, 3], |alpha| in [0.1, 3.05] rad,
    lengths |sin alpha| / k, joint angles 0 and two random): the largest absolute residual of the two end-axis
    relations; for positive twists with D replaced by -D, and as they are."""
    import random
    rng = random.Random(int(seed))
    n, worst = int(count), collections.defaultdict(float)
    for t in range(2 * n):
        k = rng.uniform(0.3, 3.0)
        al = [(1 if t >= n else -1) * rng.uniform(0.1, 3.05) for _ in range(3)]
        th = [0.0, rng.uniform(-math.pi, math.pi), rng.uniform(-math.pi, math.pi)]
        D, beta, s1, s4 = triad_end_axes([abs(math.sin(x)) / k for x in al], al, th)
        if t < n:
            worst['negative'] = max(worst['negative'], *map(abs, triad_relations(k, al, D, beta, s1, s4)))
        else:
            worst['positive, -D'] = max(worst['positive, -D'], *map(abs, triad_relations(k, al, -D, beta, s1, s4)))
            worst['positive, D'] = max(worst['positive, D'], *map(abs, triad_relations(k, al, D, beta, s1, s4)))
    print(f"positive twists with D as it is (not a relation): worst residual {worst['positive, D']:.1e}")
    print(f"positive twists, D replaced by -D: worst residual {worst['positive, -D']:.1e} over {n} triads")
    print(f"negative twists: worst residual of the two relations {worst['negative']:.1e} over {n} triads")


def t7_pairing(al_deg, k1, k2):
    """T7's two pairing conditions on each branch ('-': d4 = -d1, '+': d4 = d1) for twists al_deg and ratios k1 (links
    1-3), k2 (links 4-6): the larger relative difference of the two sides."""
    x = [math.radians(v) for v in al_deg]
    out = {}
    for branch, sg, f in (('-', 1, math.cos), ('+', -1, math.sin)):
        sides = [((1 + sg * sum(math.cos(v) for v in x[3 * t:3 * t + 3])) / k,
                  math.prod(f(v / 2) for v in x[3 * t:3 * t + 3]) / k) for t, k in ((0, k1), (1, k2))]
        out[branch] = max(abs(u - w) / max(abs(u), abs(w)) for u, w in zip(*sides))
    return out


def flip_axes(a, al_deg, d, joints):
    """The same loop with the axes of the given joints (0-based) reversed: the twists of the links before and after
    each + 180 deg, its offset negated (and its joint angle: see flip_pose); twists wrapped to (-180, 180]."""
    al, d = list(al_deg), list(d)
    for j in joints:
        al[j - 1] += 180
        al[j] += 180
        d[j] = -d[j]
    return list(a), [180 - (180 - x) % 360 for x in al], d


def flip_pose(th, joints):
    return [-x if i in joints else x for i, x in enumerate(th)]


def cmd_t7_flip(db):
    """Each T7 loop with joint axes 1, 3, 5 reversed (every twist + 180 deg, d1, d3, d5 negated): which branch's
    pairing conditions it meets with the signed ratio k = sin(alpha) / a, twists in (-180, 180] (and with |sin alpha| / a);
    and, as a check that it is the same loop, the closure of the reversed loop at up to 21 poses of the original's
    motion (the script's rigid closure) with theta1, theta3, theta5 negated."""
    def signed(a, al):
        return math.sin(math.radians(al[0])) / a[0], math.sin(math.radians(al[3])) / a[3]
    flip, worst, met, n = (0, 2, 4), 0.0, collections.Counter(), collections.Counter()
    for start, A, AL, D in t7_loops(db):
        branch, other = t7_branch(D), '+' if t7_branch(D) == '-' else '-'
        n[branch] += 1
        before = t7_pairing(AL, *signed(A, AL))
        A2, AL2, D2 = flip_axes(A, AL, D, flip)
        after, after_abs = t7_pairing(AL2, *signed(A2, AL2)), t7_pairing(AL2, kappa(A2, AL2, 0), kappa(A2, AL2, 3))
        if t7_branch(D2) == other and after[other] < 1e-9:
            met[branch] += 1
        worst = max(worst, after[other])
        al, al2 = [math.radians(x) for x in AL], [math.radians(x) for x in AL2]
        th = assemble(A, al, D)
        poses = trace(A, al, D, th, 20) if th else []
        closure = max((max(map(abs, closure_residual(A2, al2, D2, flip_pose(p, flip)))) for p in poses), default=None)
        print(f"start {start}: d4 = {branch}d1, its '{branch}' conditions {before[branch]:.1g} ('{other}': "
              f"{before[other]:.2g}); reversed: d4 = {t7_branch(D2)}d1, twists {' '.join(f'{x:.1f}' for x in AL2)} deg, "
              f"signed k {' '.join(f'{x:.4f}' for x in signed(A2, AL2))}, the '{other}' conditions {after[other]:.1g} "
              f"(|k|: {after_abs[other]:.1g}), the '{branch}' ones {after[branch]:.2g}; closure at "
              + (f"{len(poses)} poses {closure:.1g}" if poses else "no pose (no assembly found)"), flush=True)
    print(f"{met['+']} of {n['+']} '+' loops meet the '-' conditions and {met['-']} of {n['-']} '-' loops the '+' ones "
          f"after axes 1, 3, 5 are reversed (signed k, twists in (-180, 180]); worst residual {worst:.1g}")


# ---- B8: Bennett dyads at links 2-3 and 5-6 (bond fingerprint 6R/4 22 22 11 22 ...) ----
# Geometries here are (a, alpha [rad], d) triples of lists; the labelling operations are loop.hpp's.
def b8_shift(g, s):
    return tuple([v[(i + s) % 6] for i in range(6)] for v in g)


def b8_reverse(g):
    """The loop traversed backwards: joint k -> 5 - k, link k -> 4 - k (0-based, mod 6), offsets negated."""
    a, al, d = g
    return [a[(4 - k) % 6] for k in range(6)], [al[(4 - k) % 6] for k in range(6)], [-d[5 - k] for k in range(6)]


def b8_visible(g):
    """B8's five visible conditions (signed Bennett ratios k = sin(alpha) / a), lengths over
    L = sqrt(sum(a^2 + d^2) / 6)."""
    a, al, d = g
    L = math.sqrt(sum(x * x for x in a + d) / 6)
    return {'d3': d[2] / L, 'd6': d[5] / L,
            'k2 = k3': (a[1] * math.sin(al[2]) - a[2] * math.sin(al[1])) / L,
            'k5 = k6': (a[4] * math.sin(al[5]) - a[5] * math.sin(al[4])) / L,
            'd1 + d4 = d2 + d5': (d[0] + d[3] - d[1] - d[4]) / L}


def b8_labelling(g):
    """B8's labelling of a loop: the first reversal (no, yes) and shift (0..5) of its stored form with Bennett dyads at
    links 2-3 and 5-6 (signed ratios equal) and d3 = d6 = 0, each to TOL; in it, the "A form" has d1 + d4 = d2 + d5
    and is kept, the "B form" has d1 + d2 = d4 + d5 and is turned into the A form by flipping axes 2, 4, 6 and taking
    the mirror image (alpha_i -> -180 deg - alpha_i, d1, d3, d5 negated). None if neither holds to TOL.
    Returns the A-form geometry, 'A' or 'B', (reversal, shift)."""
    for r in (0, 1):
        for s in range(6):
            h = b8_shift(g, s)
            if r:
                h = b8_reverse(h)
            v = b8_visible(h)
            if max(abs(v[k]) for k in ('d3', 'd6', 'k2 = k3', 'k5 = k6')) > TOL:
                continue
            a, al, d = h
            L = math.sqrt(sum(x * x for x in a + d) / 6)
            if abs(d[0] + d[3] - d[1] - d[4]) <= TOL * L:
                return (list(a), list(al), list(d)), 'A', (r, s)
            if abs(d[0] + d[1] - d[3] - d[4]) <= TOL * L:
                return (list(a), [math.remainder(-math.pi - x, 2 * math.pi) for x in al],
                        [-d[0], d[1], -d[2], d[3], -d[4], d[5]]), 'B', (r, s)
    return None


def b8_loops(db):
    """B8's loops of a run: the unclassified loops closing to <= 1e-11 with B8's five visible conditions in some
    labelling (b8_labelling; stricter than classify's 'B8' pattern, which ignores the ratios' signs and the offsets'
    sum: of the B8 loops docs/research/discovery-5r-6r.md tabulates from an earlier run, the offsets' sum leaves out
    1406, from a cubic motion polynomial, and 2632 and 3253, of local dimension 6 and 7). Read-only. On the run of
    jobs/generic-6r.toml in g6.sqlite (docs/research/report-generic-6r.md) these are the six loops of bond fingerprint
    6R/4 22 22 11 22 ...; a fingerprint is stored only after `loopfarm bonds --store`, so it is shown, not used.
    Yields (start, fingerprint or None, rigid residual, A-form geometry, form, (reversal, shift))."""
    con = sqlite3.connect(f'file:{db}?mode=ro', uri=True)
    has_fp = any(c[1] == 'bond_fingerprint' for c in con.execute("PRAGMA table_info(candidates)"))
    q = (f"SELECT first_start, {'bond_fingerprint' if has_fp else 'NULL'}, rigid_residual, {','.join(COLS)} "
         "FROM candidates WHERE family = 'unclassified' AND joints = 6 AND rigid_residual <= 1e-11 ORDER BY first_start")
    for r in con.execute(q).fetchall():
        w = b8_labelling((list(r[3:9]), [math.radians(x) for x in r[9:15]], list(r[15:21])))
        if w:
            yield (r[0], r[1], r[2], *w)


def b8_conditions(g):
    """The eight known conditions of B8 in the A form (lengths over L): the five visible ones and
    C1 tan(alpha2/2) tan(alpha3/2) = tan(alpha5/2) tan(alpha6/2), C2 (cos alpha2 + cos alpha3)/k2 = (cos alpha5 +
    cos alpha6)/k5 (bennett_dyads' invariant), C3 tan(alpha1/2)/a1 = tan(alpha4/2)/a4, each cleared of denominators."""
    a, al, d = g
    L = math.sqrt(sum(x * x for x in a + d) / 6)
    s = [math.sin(x / 2) for x in al]
    c = [math.cos(x / 2) for x in al]
    v = b8_visible(g)
    v['C1'] = s[1] * s[2] * c[4] * c[5] - c[1] * c[2] * s[4] * s[5]
    v['C2'] = ((math.cos(al[1]) + math.cos(al[2])) * a[1] * math.sin(al[4])
               - (math.cos(al[4]) + math.cos(al[5])) * a[4] * math.sin(al[1])) / L
    v['C3'] = (a[3] * s[0] * c[3] - a[0] * c[0] * s[3]) / L
    return v


def b8_offset_conditions(g):
    """B8's two offset conditions in the A form, with k2 = sin(alpha2)/a2 (= k3), k5 = sin(alpha5)/a5 (= k6) and
    m_i = a_i / sin(alpha_i) for the joining links 1 and 4:
      L   m1 (k5 d5 - k2 d4) = m4 (k5 d1 - k2 d2)
      Q   k2 d2 d4 - k5 d1 d5 = (k5 - k2) (m1 m4 - 1/(k2 k5))        (the quadric for k2 != k5)
      Q'  m1 d4 d5 - m4 d1 d2 = (m1 - m4) (m1 m4 - 1/(k2 k5))        (the same conic for m1 != m4)
    L is multiplied by sin(alpha1) sin(alpha4), Q by sin(alpha1) sin(alpha4) k2 k5 and Q' by (sin(alpha1) sin(alpha4))^2
    k2 k5 (no m and no 1/(k2 k5) left; k2, k5 stay the signed ratios); then L and Q' are lengths, over L (the rms of the a and d), and Q is a reciprocal
    length, times L. Equivalently (d1, d2, d4, d5) = s (1/k5, 1/k2, 1/k2, 1/k5) + t (m1, m1, m4, m4) with
    1 + s^2 = k2 k5 m1 m4 (1 + t^2) (b8_parametric_offsets), which also holds when k2 = k5 or m1 = m4. L is needed:
    Q and Q' alone also admit the plane d4 = -d1, d5 = -d2, where the loop does not move."""
    a, al, d = g
    Ls = math.sqrt(sum(x * x for x in a + d) / 6)
    k2, k5 = math.sin(al[1]) / a[1], math.sin(al[4]) / a[4]
    s1, s4 = math.sin(al[0]), math.sin(al[3])
    p1, p4 = a[0] * s4, a[3] * s1  # m1 and m4 times sin(alpha1) sin(alpha4)
    g0 = k2 * k5 * a[0] * a[3] - s1 * s4  # (m1 m4 - 1/(k2 k5)) times sin(alpha1) sin(alpha4) k2 k5
    d1, d2, d4, d5 = d[0], d[1], d[3], d[4]
    return {'L': (p1 * (k5 * d5 - k2 * d4) - p4 * (k5 * d1 - k2 * d2)) / Ls,
            'Q': (k2 * k5 * s1 * s4 * (k2 * d2 * d4 - k5 * d1 * d5) - (k5 - k2) * g0) * Ls,
            "Q'": (k2 * k5 * s1 * s4 * (p1 * d4 * d5 - p4 * d1 * d2) - (p1 - p4) * g0) / Ls}


def cmd_b8_conditions(db):
    """Each B8 loop's labelling and the residuals of the ten conditions (the eight of b8_conditions, L and Q of
    b8_offset_conditions) and of Q'; the summary gives the largest of the ten."""
    loops = list(b8_loops(db))
    for start, fp, rigid, g, form, (r, s) in loops:
        print(f"start {start}: reversal {'yes' if r else 'no'}, shift {s}, "
              + ("A form (d1 + d4 = d2 + d5) as labelled" if form == 'A' else
                 "B form (d1 + d2 = d4 + d5) as labelled, axes 2, 4, 6 flipped and mirrored")
              + f"; rigid residual {rigid:.1g}; fingerprint {fp or '(not stored)'}")
    if not loops:
        print('no B8 loop')
        return
    table = {start: {**b8_conditions(g), **b8_offset_conditions(g)} for start, fp, rigid, g, form, rs in loops}
    names = list(next(iter(table.values())))
    ten = [n for n in names if n != "Q'"]
    print('condition (A form, lengths over L)'.ljust(36), ' '.join(f"{s:>8d}" for s in table))
    for n in names:
        print(n.ljust(36), ' '.join(f"{table[s][n]:+.1e}" for s in table))
    print('C1: tan(alpha2/2) tan(alpha3/2) = tan(alpha5/2) tan(alpha6/2); C2: (cos alpha2 + cos alpha3)/k2 = '
          '(cos alpha5 + cos alpha6)/k5; C3: tan(alpha1/2)/a1 = tan(alpha4/2)/a4 (each cleared of denominators)')
    print('L: m1 (k5 d5 - k2 d4) = m4 (k5 d1 - k2 d2); Q: k2 d2 d4 - k5 d1 d5 = (k5 - k2) (m1 m4 - 1/(k2 k5)); '
          "Q': m1 d4 d5 - m4 d1 d2 = (m1 - m4) (m1 m4 - 1/(k2 k5)) (m = a / sin alpha; b8_offset_conditions)")
    worst = max(((abs(v[n]), s) for s, v in table.items() for n in ten))
    worst_q = max(((abs(v["Q'"]), s) for s, v in table.items()))
    print(f"{len(table)} B8 loops, {sum(1 for x in loops if x[4] == 'B')} of them in the B form; largest residual of the "
          f"{len(ten)} conditions {worst[0]:.2g} (start {worst[1]}); of Q' {worst_q[0]:.2g} (start {worst_q[1]})")


def b8_frames(a, al, d, th):
    F = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    out = [F]
    for i in range(6):
        F = mat_mul(F, dh(th[i], d[i], a[i], al[i]))
        out.append(F)
    return out


def b8_twists(a, al, d, th):
    """Spatial twists (omega, v) of the six joints and of the 18 parameters a1..a6, alpha1..alpha6, d1..d6 at the
    pose th: the joints' screws, and each parameter's displacement of the links after it."""
    Fs = b8_frames(a, al, d, th)
    St, Sp = [], [None] * 18
    for i in range(6):
        R = [row[:3] for row in Fs[i][:3]]
        p = [Fs[i][0][3], Fs[i][1][3], Fs[i][2][3]]

        def spatial(w, v):
            W, V = [dot(r, w) for r in R], [dot(r, v) for r in R]
            pw = cross(p, W)
            return W + [V[k] + pw[k] for k in range(3)]
        z, x = [0.0, 0.0, 1.0], [math.cos(th[i]), math.sin(th[i]), 0.0]
        foot = [a[i] * x[0], a[i] * x[1], d[i]]
        St.append(spatial(z, [0.0, 0.0, 0.0]))
        Sp[i] = spatial([0.0, 0.0, 0.0], x)               # a_i: a slide along the common normal
        Sp[6 + i] = spatial(x, cross(foot, x))            # alpha_i: a turn about the normal through its far foot
        Sp[12 + i] = spatial([0.0, 0.0, 0.0], z)          # d_i: a slide along the axis
    return St, Sp


def b8_motion_poses(loopfarm, g, count):
    """count poses spread over the first circuit of `loopfarm motion` of g, each closed by the script's rigid closure
    to <= 1e-9 (poses that do not are dropped)."""
    a, al, d = g
    out = subprocess.run([loopfarm, 'motion', '--a', ','.join(map(repr, a)), '--alpha-deg=' + ','.join(
        repr(math.degrees(x)) for x in al), '--d=' + ','.join(map(repr, d)), '--csv', '-'], capture_output=True, text=True)
    rows_ = [r for r in out.stdout.splitlines() if r]
    if len(rows_) < 2:
        return []
    head = rows_[0].split(',')
    data = [dict(zip(head, r.split(','))) for r in rows_[1:]]
    data = [r for r in data if r['circuit'] == data[0]['circuit']]
    poses = []
    for i in sorted(set(int(i * (len(data) - 1) / (count - 1)) for i in range(count))):
        th = [math.radians(float(data[i][f'theta{k}_deg'])) for k in range(1, 7)]
        for _ in range(8):
            if max(map(abs, closure_residual(a, al, d, th))) < 1e-15:
                break
            th, _ = lm_close(a, al, d, th, [1, 2, 3, 4, 5], 3, 1e-12)
        if max(map(abs, closure_residual(a, al, d, th))) < 1e-9:
            poses.append(th)
    return poses


def b8_normal_rows(g, poses):
    """The reciprocal-wrench method: at each pose of the motion the six joint screws are dependent, and the unit wrench
    w reciprocal to all of them turns the closure's first-order change under a parameter change dp into the scalar
    sum_j (w . S_pj) dp_j, which must vanish for the changed loop to close near that pose. The rows (w . S_pj)_j over
    the poses span the normal space of the movable set at g; its rank is the number of conditions."""
    out = []
    for th in poses:
        St, Sp = b8_twists(*g, th)
        w = sym_eig([[sum(S[i] * S[j] for S in St) for j in range(6)] for i in range(6)])[1][0]
        out.append([dot(w, S) for S in Sp])
    return out


def singular_values_of(M):
    """Singular values (descending) of a matrix given by its rows: one-sided Jacobi (Hestenes) on the columns, accurate
    to round-off relative to the largest (the Gram matrix's eigenvalues would square the precision)."""
    U = [list(col) for col in zip(*M)]
    for _ in range(60):
        off = 0.0
        for p in range(len(U)):
            for q in range(p + 1, len(U)):
                x, y, z = dot(U[p], U[p]), dot(U[q], U[q]), dot(U[p], U[q])
                if x * y == 0.0 or abs(z) <= 1e-16 * math.sqrt(x * y):
                    continue
                off = max(off, abs(z) / math.sqrt(x * y))
                zeta = (y - x) / (2 * z)
                t = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(1 + zeta * zeta))
                c = 1 / math.sqrt(1 + t * t)
                s = c * t
                U[p], U[q] = [c * u - s * v for u, v in zip(U[p], U[q])], [s * u + c * v for u, v in zip(U[p], U[q])]
        if off < 1e-15:
            break
    return sorted((math.sqrt(dot(u, u)) for u in U), reverse=True)


def b8_count(loopfarm, g, count=40):
    """The reciprocal-wrench count at g: the singular values (descending) of the normal rows at `count` poses of its
    motion over the 18 parameters, and the number of conditions, those above the largest gap (ratio of neighbours; the
    rows' round-off, ~1e-12, is far below the smallest condition's, >= 1e-5 at B8's loops). None if fewer than 20 poses."""
    poses = b8_motion_poses(loopfarm, g, count)
    if len(poses) < 20:
        return None
    rows_ = b8_normal_rows(g, poses)
    sv = singular_values_of(rows_)
    floor = [max(x, 1e-17 * sv[0]) for x in sv]
    return rows_, sv, max(range(1, 18), key=lambda i: floor[i - 1] / floor[i])


def b8_known_in_normal_space(g, rows_, n):
    """The gradients of B8's eight known conditions (b8_conditions) over the 18 parameters: the largest relative part
    of one outside the span of the n leading normal directions, and the gradients' rank (singular values above 1e-6
    of the largest, gradients scaled to 1)."""
    basis, rest = [], [list(r) for r in rows_]
    for _ in range(n):  # Gram-Schmidt with pivoting
        r = max(rest, key=lambda x: dot(x, x))
        u = [x / math.sqrt(dot(r, r)) for x in r]
        basis.append(u)
        rest = [[x - dot(v, u) * y for x, y in zip(v, u)] for v in rest]
    grads = []
    for j in range(18):
        gp, gm = [list(v) for v in g], [list(v) for v in g]
        gp[j // 6][j % 6] += 1e-6
        gm[j // 6][j % 6] -= 1e-6
        cp, cm = b8_conditions(gp), b8_conditions(gm)
        grads.append([(cp[k] - cm[k]) / 2e-6 for k in cp])
    grads = [[x / math.sqrt(sum(y * y for y in col)) for x in col] for col in zip(*grads)]  # one row per condition
    outside = 0.0
    for v in grads:
        w = list(v)
        for u in basis:
            w = [x - dot(v, u) * y for x, y in zip(w, u)]
        outside = max(outside, math.sqrt(dot(w, w)))
    sv = singular_values_of(grads)
    return outside, sum(1 for x in sv if x > 1e-6 * sv[0])


def cmd_b8_count(db, loopfarm):
    """The number of B8's conditions at each B8 loop (A form) by the reciprocal-wrench method (b8_count, 40 poses of
    its `loopfarm motion`), the dimension of its movable set 18 less that; and whether the eight known conditions are
    among them (b8_known_in_normal_space)."""
    found, known, worst = collections.Counter(), collections.Counter(), 0.0
    for start, fp, rigid, g, form, rs in b8_loops(db):
        c = b8_count(loopfarm, g)
        if c is None:
            print(f"start {start}: motion not traced to 20 poses, not counted")
            continue
        rows_, sv, n = c
        found[n] += 1
        outside, rank = b8_known_in_normal_space(g, rows_, n)
        known[rank] += 1
        worst = max(worst, outside)
        print(f"start {start}: {len(rows_)} poses; singular values {' '.join(f'{x:.1e}' for x in sv)}; largest gap "
              f"{sv[n - 1]:.1e} to {sv[n]:.1e}: {n} conditions, dimension {18 - n}; the 8 known conditions' gradients "
              f"rank {rank}, outside that normal space <= {outside:.0e}", flush=True)
    print('; '.join(f"{k} loops: {n} conditions, dimension {18 - n}" for n, k in sorted(found.items()))
          + '; the 8 known conditions ' + ', '.join(f"of rank {r} at {k} loops" for r, k in sorted(known.items()))
          + f", outside the normal space <= {worst:.0e}")


def b8_to_q(g):
    """The 13 parameters B8's visible conditions leave (A form): k2, alpha2, alpha3, k5, alpha5, alpha6, a1, alpha1,
    a4, alpha4, d1, d2, d4 (k2 = k3, k5 = k6 the dyads' signed ratios; d3 = d6 = 0, d5 = d1 + d4 - d2)."""
    a, al, d = g
    return [math.sin(al[1]) / a[1], al[1], al[2], math.sin(al[4]) / a[4], al[4], al[5], a[0], al[0], a[3], al[3],
            d[0], d[1], d[3]]


def b8_from_q(q):
    k2, al2, al3, k5, al5, al6, a1, al1, a4, al4, d1, d2, d4 = q
    return ([a1, math.sin(al2) / k2, math.sin(al3) / k2, a4, math.sin(al5) / k5, math.sin(al6) / k5],
            [al1, al2, al3, al4, al5, al6], [d1, d2, 0.0, d4, d1 + d4 - d2, 0.0])


def b8_solve_c123(q):
    """alpha6, k5 and a4 from C1, C2 and C3, the other parameters as given."""
    q = list(q)
    t = lambda x: math.tan(x / 2)
    q[5] = 2 * math.atan(t(q[1]) * t(q[2]) / t(q[4]))                                      # C1
    q[3] = q[0] * (math.cos(q[4]) + math.cos(q[5])) / (math.cos(q[1]) + math.cos(q[2]))   # C2
    q[8] = q[6] * t(q[9]) / t(q[7])                                                       # C3
    return q


def b8_pose_error(g, th):
    """The closure error at a pose as a 6-vector: the rotation's axial part and the translation."""
    F = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    for i in range(6):
        F = mat_mul(F, dh(th[i], g[2][i], g[0][i], g[1][i]))
    return [(F[2][1] - F[1][2]) / 2, (F[0][2] - F[2][0]) / 2, (F[1][0] - F[0][1]) / 2, F[0][3], F[1][3], F[2][3]]


def b8_close(q, poses, held, free=(10, 11, 12), iters=80):
    """Levenberg-Marquardt on the closure at every pose: the unknowns the parameters q[free] (the offsets d1, d2, d4)
    and at each pose k the joint angles but the held one (held[k]). Returns q, poses and the root-sum-square closure
    error over the poses."""
    q, poses = list(q), [list(t) for t in poses]

    def error(q, poses):
        g = b8_from_q(q)
        return [x for th in poses for x in b8_pose_error(g, th)]
    r = error(q, poses)
    s, lam = sum(x * x for x in r), 1e-6
    for _ in range(iters):
        if s < 1e-28:
            break
        g = b8_from_q(q)
        tw = [b8_twists(*g, th) for th in poses]
        cols = []
        for j in free:  # d p / d q_j by central differences, through the parameters' twists
            qp, qm = list(q), list(q)
            qp[j] += 1e-7
            qm[j] -= 1e-7
            gp, gm = b8_from_q(qp), b8_from_q(qm)
            dp = [(x - y) / 2e-7 for x, y in zip(gp[0] + gp[1] + gp[2], gm[0] + gm[1] + gm[2])]
            cols.append([sum(dp[i] * Sp[i][m] for i in range(18)) for St, Sp in tw for m in range(6)])
        for k, (St, Sp) in enumerate(tw):
            for jj in range(6):
                if jj != held[k]:
                    cols.append([St[jj][m] if kk == k else 0.0 for kk in range(len(poses)) for m in range(6)])
        A = [[dot(ci, cj) for cj in cols] for ci in cols]
        b = [-dot(ci, r) for ci in cols]
        for _ in range(12):
            step = solve([[x + (lam if i == j else 0.0) for j, x in enumerate(row)] for i, row in enumerate(A)], b)
            q2, P2 = list(q), [list(t) for t in poses]
            for n, j in enumerate(free):
                q2[j] += step[n]
            n = len(free)
            for k in range(len(poses)):
                for jj in range(6):
                    if jj != held[k]:
                        P2[k][jj] += step[n]
                        n += 1
            r2 = error(q2, P2)
            s2 = sum(x * x for x in r2)
            if s2 < s:
                q, poses, r, s, lam = q2, P2, r2, s2, max(lam / 10, 1e-15)
                break
            lam *= 10
        else:
            break
    return q, poses, math.sqrt(s)


def b8_held(g, poses):
    """At each pose, the joint that turns fastest along the motion (the largest part of the joint screws' null vector):
    held while the others are solved, so that no pose sits at a turning point of its held joint."""
    out = []
    for th in poses:
        St = b8_twists(*g, th)[0]
        v = sym_eig([[dot(St[i], St[j]) for j in range(6)] for i in range(6)])[1][0]
        out.append(max(range(6), key=lambda i: abs(v[i])))
    return out


def cmd_b8_build(db, seed, count, eps, loopfarm, size=0.005, npose=12):
    """Loops built from C1-C3: the i-th starts from B8 loop i mod (their number) in the A form, its parameters k2, alpha2,
    alpha3, alpha5, a1, alpha1, alpha4 moved at random (uniform, size 0.005, relative for k2 and a1), then alpha6, k5
    and a4 solved from C1, C2, C3 and the offsets d1, d2, d4 (the two offset conditions being unknown) by closing the
    loop at 12 poses of the original's motion (`loopfarm motion`); kept if it closes to <= 1e-11 there, and checked
    with `loopfarm verify`. Near misses: each verified one with alpha6 moved by EPS (C1 off), k5 scaled by 1 + EPS
    (C2 off) or a4 scaled by 1 + EPS (C3 off), the offsets and poses solved again from the verified loop's: does it close?"""
    import random
    rng = random.Random(int(seed))
    eps = float(eps)
    loops = list(b8_loops(db))
    if not loops:
        sys.exit('no B8 loop')
    base, built, near, tried, counted = {}, 0, collections.Counter(), 0, collections.Counter()
    for i in range(int(count)):
        start, fp, rigid, g, form, rs = loops[i % len(loops)]
        if start not in base:
            poses = b8_motion_poses(loopfarm, g, npose)
            base[start] = (poses, b8_held(g, poses))
        poses, held = base[start]
        q = b8_to_q(g)
        for j in (0, 1, 2, 4, 6, 7, 9):
            q[j] += size * rng.uniform(-1, 1) * (abs(q[j]) if j in (0, 6) else 1)
        q, P, res = b8_close(b8_solve_c123(q), poses, held)
        a, al, d = b8_from_q(q)
        j = verify(loopfarm, a, [math.degrees(x) for x in al], d) if res <= 1e-11 else {}
        line = f"{i}: from start {start}, closure at {len(P)} poses {res:.1e}"
        if j:
            line += (f"; loopfarm verify: verified {j['verified']}, E_mean {j['E_mean']:.1g}, local dimension "
                     f"{j['local_dimension']}")
        if j.get('verified'):
            built += 1
            c = b8_count(loopfarm, (a, al, d))
            counted[c[2] if c else None] += 1
            line += f"; by the wrench method {c[2]} conditions, dimension {18 - c[2]}" if c else "; not counted"
            miss = []
            for name, k, f in (('C1', 5, lambda x: x + eps), ('C2', 3, lambda x: x * (1 + eps)),
                               ('C3', 8, lambda x: x * (1 + eps))):
                q2 = list(q)
                q2[k] = f(q2[k])
                q2, P2, r2 = b8_close(q2, P, held)
                a2, al2, d2 = b8_from_q(q2)
                ok = r2 <= 1e-11 and verify(loopfarm, a2, [math.degrees(x) for x in al2], d2)['verified']
                near[name, ok] += 1
                tried += 1
                miss.append(f"{name} off: closure {r2:.1e}{' verified' if ok else ''}")
            line += '; ' + ', '.join(miss)
        print(line, flush=True)
    closed = sum(v for (n, ok), v in near.items() if ok)
    dims = [f"{k} with {n} conditions, dimension {18 - n}" for n, k in sorted(x for x in counted.items() if x[0])]
    print(f"{built} of {count} built verified ({', '.join(dims + [f'{counted[None]} not counted'] * (None in counted))})"
          + f", {closed} of {tried} near misses close (EPS {eps:g}; "
          + ', '.join(f"{n} off: {near[n, True]} of {near[n, True] + near[n, False]}" for n in ('C1', 'C2', 'C3')) + ')')


def b8_parametric_offsets(k2, k5, m1, m4, s, t):
    """B8's offsets in the A form from the parametric form of L and Q: (d1, d2, d4, d5) = s (1/k5, 1/k2, 1/k2, 1/k5) +
    t (m1, m1, m4, m4), d3 = d6 = 0 (a member when 1 + s^2 = k2 k5 m1 m4 (1 + t^2))."""
    return [s / k5 + t * m1, s / k2 + t * m1, 0.0, s / k2 + t * m4, s / k5 + t * m4, 0.0]


def b8_random_geometry(rng):
    """A random geometry meeting B8's ten conditions, A form, every twist negative: the dyads' ratio k2 in [-2, -0.4] and
    twists alpha2, alpha3, alpha5 in (-180, 0) deg (8.6 deg from the ends), alpha6 from C1 and k5 from C2; a1 in
    [0.3, 2], alpha1, alpha4 as the dyads' twists, a4 from C3; t in [-1.5, 1.5] and s = +-sqrt(k2 k5 m1 m4 (1 + t^2) - 1)
    (redrawn when alpha6, k5 or a4 fall outside (-180, 0) deg 5.7 deg from the ends, [-5, -0.2), (0.1, 5), or no t of
    20 gives a real s). Returns a, alpha [rad], k2, k5, m1, m4, s, t."""
    t2 = lambda x: math.tan(x / 2)
    while True:
        k2 = -rng.uniform(0.4, 2.0)
        al2, al3, al5 = (-rng.uniform(0.15, math.pi - 0.15) for _ in range(3))
        al6 = 2 * math.atan(t2(al2) * t2(al3) / t2(al5))
        if not (-math.pi + 0.1 < al6 < -0.1):
            continue
        k5 = k2 * (math.cos(al5) + math.cos(al6)) / (math.cos(al2) + math.cos(al3))
        if k5 >= -0.2 or k5 < -5:
            continue
        a1 = rng.uniform(0.3, 2.0)
        al1, al4 = -rng.uniform(0.15, math.pi - 0.15), -rng.uniform(0.15, math.pi - 0.15)
        a4 = a1 * t2(al4) / t2(al1)
        if not 0.1 < a4 < 5:
            continue
        a = [a1, math.sin(al2) / k2, math.sin(al3) / k2, a4, math.sin(al5) / k5, math.sin(al6) / k5]
        m1, m4 = a1 / math.sin(al1), a4 / math.sin(al4)
        for _ in range(20):
            t = rng.uniform(-1.5, 1.5)
            s2 = k2 * k5 * m1 * m4 * (1 + t * t) - 1
            if s2 > 0:
                break
        else:
            continue
        return a, [al1, al2, al3, al4, al5, al6], k2, k5, m1, m4, math.copysign(math.sqrt(s2), rng.uniform(-1, 1)), t


def cmd_b8_build10(seed, count, eps, loopfarm):
    """Loops built from all ten of B8's conditions (b8_random_geometry, offsets from b8_parametric_offsets, not solved by
    closure; random geometry, not near the run's loops), each checked with `loopfarm verify`; one that is not verified
    is tried with the script's rigid closure from 300 random starts (assemble): does it assemble at all? Near misses of
    each: s scaled by 1 + EPS (Q off, L kept) and d1, d2 both moved by EPS L (L off, d1 + d4 = d2 + d5 kept; L the rms
    of the a and d): does `loopfarm verify` find them moving?"""
    import random
    rng = random.Random(int(seed))
    eps = float(eps)
    built, nowhere, stuck, near, tried, worst = 0, 0, 0, collections.Counter(), 0, 0.0
    deg = lambda al: [math.degrees(x) for x in al]
    for i in range(int(count)):
        a, al, k2, k5, m1, m4, s, t = b8_random_geometry(rng)
        d = b8_parametric_offsets(k2, k5, m1, m4, s, t)
        L = math.sqrt(sum(x * x for x in a + d) / 6)
        res = max(abs(v) for v in {**b8_conditions((a, al, d)), **b8_offset_conditions((a, al, d))}.values())
        worst = max(worst, res)
        j = verify(loopfarm, a, deg(al), d)
        line = (f"{i}: k2 {k2:.3f} k5 {k5:.3f} m1 {m1:.3f} m4 {m4:.3f} s {s:+.3f} t {t:+.3f}; conditions <= {res:.0e}; "
                f"verified {j['verified']}")
        if j['verified']:
            built += 1
            line += f", E_mean {j['E_mean']:.1g}, local dimension {j['local_dimension']}"
        elif assemble(a, al, d) is None:
            nowhere += 1
            line += f" (rigid residual {j['rigid_residual']:.1g}; assembles nowhere from 300 starts)"
        else:
            stuck += 1
            line += f" (rigid residual {j['rigid_residual']:.1g}; assembles)"
        for name, dd in (('Q off', b8_parametric_offsets(k2, k5, m1, m4, s * (1 + eps), t)),
                         ('L off', [d[0] + eps * L, d[1] + eps * L, 0.0, d[3], d[4], 0.0])):
            jj = verify(loopfarm, a, deg(al), dd)
            near[name] += bool(jj['verified'])
            tried += 1
            off = b8_offset_conditions((a, al, dd))
            line += (f"; {name} (L {off['L']:+.0e}, Q {off['Q']:+.0e}): verified {jj['verified']}, rigid residual "
                     f"{jj['rigid_residual']:.1g}")
        print(line, flush=True)
    why = ', '.join(x for x in (f"{nowhere} assemble nowhere" * bool(nowhere),
                                f"{stuck} assemble but do not move" * bool(stuck)) if x)
    print(f"{built} of {count} built verified" + (f" ({why})" if why else '') + f", {sum(near.values())} of {tried} near "
          f"misses move (EPS {eps:g}; Q off {near['Q off']}, L off {near['L off']}); the ten conditions hold to "
          f"<= {worst:.0e} on the built loops")


# ---- The near-miss classes: near (trivial set), locked-bennett, triad-reorder ----
def class_rows(db, fingerprint):
    """The unclassified loops whose bond fingerprint starts with fingerprint (read-only): start, rigid residual,
    E_mean, local dimension, fingerprint, a, alpha [deg], d."""
    con = sqlite3.connect(f'file:{db}?mode=ro', uri=True)
    q = (f"SELECT first_start, rigid_residual, E_mean, local_dimension, bond_fingerprint, {','.join(COLS)} "
         "FROM candidates WHERE family = 'unclassified' AND substr(bond_fingerprint, 1, length(?1)) = ?1 "
         "ORDER BY first_start")
    return [(r[0], r[1], r[2], r[3], r[4], list(r[5:11]), list(r[11:17]), list(r[17:23]))
            for r in con.execute(q, (fingerprint,))]


def geometry_args(a, al_deg, d):
    return ['--a=' + ','.join(map(repr, a)), '--alpha-deg=' + ','.join(map(repr, al_deg)), '--d=' + ','.join(map(repr, d))]


def niced(cmd):
    return subprocess.run(['nice', '-n', '15'] + cmd, capture_output=True, text=True)


def verify_niced(loopfarm, a, al_deg, d):
    return json.loads(niced([loopfarm, 'verify', '--json'] + geometry_args(a, al_deg, d)).stdout)


def circuit_travels(j):
    """Each joint's travel [rad] over the circuit `loopfarm verify --json` reports (None if it reports none)."""
    if not j.get('circuits') or not j.get('circuit'):
        return None
    return [math.radians(x['range_deg'][1] - x['range_deg'][0]) for x in j['circuits'][j['circuit'] - 1]['joints']]


def motion_poses(loopfarm, a, al_deg, d, circuit=None):
    """The poses (joint angles [rad]) of `loopfarm motion --csv` on one circuit (default: the first listed)."""
    out = niced([loopfarm, 'motion', '--csv', '-'] + geometry_args(a, al_deg, d)).stdout.splitlines()
    if len(out) < 2:
        return []
    head = out[0].split(',')
    data = [dict(zip(head, r.split(','))) for r in out[1:] if r]
    want = str(circuit) if circuit is not None else (data[0]['circuit'] if data else None)
    return [[math.radians(float(r[f'theta{k}_deg'])) for k in range(1, len(a) + 1)] for r in data if r['circuit'] == want]


def joint_axes(a, al, d, th):
    """Joint axis i as (point, unit direction): z of frame i-1 (frame 0 = the base), the DH convention above."""
    F = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]
    out = []
    for i in range(len(a)):
        out.append(([F[0][3], F[1][3], F[2][3]], [F[0][2], F[1][2], F[2][2]]))
        F = mat_mul(F, dh(th[i], d[i], a[i], al[i]))
    return out


def axis_gap(l1, l2):
    """How near two lines are to one: max(|sin angle|, distance), and the two."""
    (p1, w1), (p2, w2) = l1, l2
    c = cross(w1, w2)
    s = math.sqrt(dot(c, c))
    dp = [y - x for x, y in zip(p1, p2)]
    if s > 1e-9:
        dist = abs(dot(dp, c)) / s
    else:  # parallel: the distance of p2 from line 1
        t = dot(dp, w1)
        dist = math.sqrt(max(0.0, dot(dp, dp) - t * t))
    return max(s, dist), s, dist


def common_normal(l1, l2):
    """The common normal of two skew lines: distance, |sin angle|, its feet as parameters t1 on l1, t2 on l2."""
    (p1, w1), (p2, w2) = l1, l2
    c = cross(w1, w2)
    s = math.sqrt(dot(c, c))
    dp = [y - x for x, y in zip(p1, p2)]
    b, e, f = dot(w1, w2), dot(dp, w1), dot(dp, w2)
    den = 1 - b * b
    return abs(dot(dp, c)) / s, s, (e - b * f) / den, (b * e - f) / den


def fold_residual(a, al_deg, d, k):
    """Joint k (0-based) folds the loop when the links on either side are equal and d_k = 0: axes k-1 and k+1
    coincide at theta_k = 180 deg, the trivial set. Residual max(|a_{k-1} - a_k|, |sin(alpha_{k-1} - alpha_k)|, |d_k|)."""
    return max(abs(a[k - 1] - a[k]), abs(math.sin(math.radians(al_deg[k - 1] - al_deg[k]))), abs(d[k]))


def cmd_near(db, loopfarm, fingerprint, full=1.0):
    """Per loop of the class: the joint with the least fold residual; the nearest two joint axes over the poses of
    `loopfarm motion --csv` (circuit as verify reports it) and the joint angles there; each joint's travel over that
    circuit, the least, and the largest of the joints that do not turn fully (travel < 2 pi - full rad: the rocking);
    the nearest family (least residual of `loopfarm verify --json`)."""
    loops = class_rows(db, fingerprint)
    print(f"{len(loops)} loops of fingerprint {fingerprint!r}")
    print("| start | dim | rigid (verify) | verified | fold: joint, residual | nearest axes, gap (sin, dist) | "
          "least travel [rad] (joint) | largest rocking [rad] (joints) | nearest family, residual |")
    print("|---|---|---|---|---|---|---|---|---|")
    summary = collections.defaultdict(list)
    for start, rigid, e_mean, dim, fp, a, al_deg, d in loops:
        n = len(a)
        al = [math.radians(x) for x in al_deg]
        fold, fk = min((fold_residual(a, al_deg, d, k), k) for k in range(n))
        j = verify_niced(loopfarm, a, al_deg, d)
        travel = circuit_travels(j)
        fam = {k: x for k, x in j['family_residuals'].items() if x is not None}
        near = min(fam.items(), key=lambda kv: kv[1]) if fam else ('?', float('nan'))
        best = (float('inf'), 0, 0, 0.0, 0.0, [])
        for th in motion_poses(loopfarm, a, al_deg, d, j.get('circuit')):
            ax = joint_axes(a, al, d, th)
            for i in range(n):
                for k in range(i + 1, n):
                    g, s, dist = axis_gap(ax[i], ax[k])
                    if g < best[0]:
                        best = (g, i, k, s, dist, th)
        g, i, k, s, dist, th = best
        kind = ('adjacent' if (k - i) in (1, n - 1) else 'across one joint' if (k - i) in (2, n - 2) else 'opposite')
        if travel:
            least = min(range(n), key=lambda m: travel[m])
            rock = [m for m in range(n) if travel[m] < 2 * math.pi - full]
            big = max(rock, key=lambda m: travel[m]) if rock else None
            trav = f"{travel[least]:.2g} ({least + 1})"
            rocking = f"{travel[big]:.2g} ({','.join(str(m + 1) for m in rock)})" if rock else '-'
            summary['least'].append(travel[least])
            if rock:
                summary['rocking'].append(travel[big])
        else:
            trav = rocking = 'no circuit'
        summary['fold'].append(fold)
        summary['gap'].append(g)
        summary[kind].append(start)
        print(f"| {start} | {dim} | {g2(j['rigid_residual'])} | {j['verified']} | {fk + 1}, {fold:.2g} | "
              f"{i + 1},{k + 1} ({kind}), {g:.2g} ({s:.2g}, {dist:.2g}) | {trav} | {rocking} | {near[0]} {near[1]:.3g} |")
        sys.stdout.flush()
    rng = lambda key: f"{min(summary[key]):.2g}..{max(summary[key]):.2g}" if summary[key] else '-'
    print(f"fold residual {rng('fold')}; axis gap {rng('gap')}; least travel {rng('least')}; largest rocking "
          f"{rng('rocking')}; nearest axes " + ', '.join(f"{kind} in {len(summary[kind])}" for kind in
                                                         ('adjacent', 'across one joint', 'opposite') if summary[kind]))


def g2(x):
    return 'None' if x is None else f'{x:.2g}'


def bennett_triad(a, al_deg, d, tol=TOL):
    """The first run of three consecutive links k, k+1, k+2 (0-based k) with one Bennett ratio and no offset at the two
    joints inside it (k+1, k+2), to tol: the best such k as (largest ratio difference or inside |d|, k), or None."""
    n, found = len(a), []
    for k in range(n):
        ks = [kappa(a, al_deg, (k + i) % n) for i in range(3)]
        res = max(max(ks) - min(ks), abs(d[(k + 1) % n]), abs(d[(k + 2) % n]))
        if res < tol * max(1.0, ks[0]):
            found.append((res, k))
    return min(found) if found else None


def bennett_4r(poses, a, al, d, moving):
    """The 4R of the four moving axes (in loop order) in each pose: ranges over the poses of Bennett's conditions
    (opposite links equal in a and |sin alpha|, one ratio |sin alpha| / a, the offsets along each axis zero). Link 3
    (from the last moving axis back to the first) is the merged link over the locked joints."""
    stats = {}
    for th in poses:
        ax = joint_axes(a, al, d, th)
        L = [ax[m] for m in moving]
        links = [common_normal(L[i], L[(i + 1) % 4]) for i in range(4)]
        offs = [links[i][2] - links[i - 1][3] for i in range(4)]
        kap = [s / dd for dd, s, _, _ in links]
        vals = {'merged vs opposite a': abs(links[3][0] - links[1][0]),
                'merged vs opposite |sin|': abs(links[3][1] - links[1][1]),
                'other pair a': abs(links[0][0] - links[2][0]), 'other pair |sin|': abs(links[0][1] - links[2][1]),
                'ratio spread': max(kap) - min(kap), 'largest |offset|': max(abs(x) for x in offs)}
        for key, x in vals.items():
            lo, hi = stats.get(key, (float('inf'), 0.0))
            stats[key] = (min(lo, x), max(hi, x))
    return stats


def pattern_gap(p, q):
    """The largest parameter difference of two loops after scaling each to mean a = 1 (twists up to sign, offsets up
    to sign), least over q's shifts, reversals and mirror image: (gap, labelling)."""
    def gap(p, q):
        (a1, al1, d1), (a2, al2, d2) = p, q
        s1, s2 = sum(a1) / len(a1), sum(a2) / len(a2)
        w = lambda x: abs((x + math.pi) % (2 * math.pi) - math.pi)
        return max(max(abs(x / s1 - y / s2) for x, y in zip(a1, a2)),
                   max(min(w(math.radians(x - y)), w(math.radians(x + y))) for x, y in zip(al1, al2)),
                   max(abs(abs(x / s1) - abs(y / s2)) for x, y in zip(d1, d2)))
    a, al, d = q
    n, best = len(a), (float('inf'), '')
    for mirror in (1, -1):
        AL0, D0 = [mirror * x for x in al], [mirror * x for x in d]
        for s in range(n):
            A, AL, D = [a[(i + s) % n] for i in range(n)], [AL0[(i + s) % n] for i in range(n)], [D0[(i + s) % n] for i in range(n)]
            m = ' mirror' if mirror < 0 else ''
            best = min(best, (gap(p, (A, AL, D)), f'shift {s}{m}'),
                       (gap(p, ([A[(n - 2 - i) % n] for i in range(n)], [AL[(n - 2 - i) % n] for i in range(n)],
                                [D[(n - 1 - i) % n] for i in range(n)])), f'shift {s} reversed{m}'))
    return best


def cmd_locked_bennett(db, loopfarm, fingerprint):
    """Per loop of the class: the Bennett-ratio triad (links k, k+1, k+2, one ratio, d = 0 inside), the two joints
    outside it (k+4, k+5, joints numbered so that link i runs from joint i to joint i+1) and their travel over
    verify's circuit, whether they are the two least travelled, and Bennett's conditions on the 4R of the four other
    axes over the poses of `loopfarm motion --csv` (its first circuit). Then how far apart the members are."""
    loops = class_rows(db, fingerprint)
    print(f"{len(loops)} loops of fingerprint {fingerprint!r}")
    for start, rigid, e_mean, dim, fp, a, al_deg, d in loops:
        n = len(a)
        t = bennett_triad(a, al_deg, d)
        if t is None:
            print(f"start {start}: no Bennett-ratio triad")
            continue
        res, k = t
        links = [(k + i) % n for i in range(3)]
        locked = [(k + 4) % n, (k + 5) % n]
        moving = [(k + i) % n for i in range(4)]
        outer = max(abs(a[links[0]] - a[links[2]]), abs(wrapd(al_deg[links[0]] - al_deg[links[2]])) / 57.3)
        j = verify_niced(loopfarm, a, al_deg, d)
        travel = circuit_travels(j)
        if travel:
            two = sorted(range(n), key=lambda m: travel[m])[:2]
            trav = (f"travel {travel[locked[0]]:.2g}, {travel[locked[1]]:.2g} rad "
                    f"({'the two least' if sorted(two) == sorted(locked) else 'least: ' + ','.join(str(m + 1) for m in two)};"
                    f" the others {' '.join(f'{travel[m]:.2g}' for m in moving)})")
        else:
            trav = 'no circuit reported'
        stats = bennett_4r(motion_poses(loopfarm, a, al_deg, d), a, [math.radians(x) for x in al_deg], d, moving)
        print(f"start {start} (dim {dim}): triad links {','.join(str(m + 1) for m in links)}, ratio "
              f"{kappa(a, al_deg, links[0]):.6f} (ratio spread and inside |d| <= {res:.0e}), outer links {links[0] + 1} = "
              f"{links[2] + 1} to {outer:.0e}; joints {locked[0] + 1},{locked[1] + 1} nearly locked: {trav}")
        print(f"  4R of axes {','.join(str(m + 1) for m in moving)}, over the poses: " +
              '; '.join(f'{key} {lo:.2g}..{hi:.2g}' for key, (lo, hi) in stats.items()))
        sys.stdout.flush()
    for x, y in ((x, y) for i, x in enumerate(loops) for y in loops[i + 1:]):
        g, name = pattern_gap(tuple(x[5:8]), tuple(y[5:8]))
        print(f"start {x[0]} vs {y[0]}: least parameter gap over relabellings and mirror {g:.3g} ({name})")


def cmd_triad_reorder(db, loopfarm, start, first):
    """The loop at START with the links of its triad (FIRST, FIRST+1, FIRST+2) put in each of the six orders (twist
    and a together; offsets kept): `loopfarm verify`'s exit code (0: a circuit moves) and its family and detail."""
    con = sqlite3.connect(f'file:{db}?mode=ro', uri=True)
    v = con.execute(f"SELECT {','.join('c.' + x for x in COLS)} FROM candidates c JOIN starts s USING (candidate_id) "
                    "WHERE s.start_index = ?", (int(start),)).fetchone()
    a, al, d = list(v[0:6]), list(v[6:12]), list(v[12:18])
    idx = [(int(first) - 1 + i) % 6 for i in range(3)]
    ks = [kappa(a, al, i) for i in idx]
    print(f"start {start}: triad links {','.join(str(i + 1) for i in idx)}, ratios {' '.join(f'{x:.9f}' for x in ks)}, "
          f"offsets inside {d[idx[1]]:.1e}, {d[idx[2]]:.1e}")
    moved = 0
    for p in itertools.permutations(idx):
        A, AL = list(a), list(al)
        for i, k in zip(idx, p):
            A[i], AL[i] = a[k], al[k]
        r = niced([loopfarm, 'verify'] + geometry_args(A, AL, d))
        lines = [l.strip() for l in r.stdout.splitlines()]
        fam = next((l.split()[-1] for l in lines if l.startswith('family ')), '?')
        det = next((l.split(None, 1)[1] for l in lines if l.startswith('detail ')), '')
        moved += r.returncode == 0
        verdict_ = 'moves' if r.returncode == 0 else 'rigid' if r.returncode == 4 else f'exit {r.returncode}'
        print(f"  links in the order {','.join(str(k + 1) for k in p)}: {verdict_}, {fam}" + (f" ({det})" if det else ''))
        sys.stdout.flush()
    print(f"  {moved} of 6 orders move")


if __name__ == '__main__':
    if len(sys.argv) >= 3 and sys.argv[1] == 'classes':
        cmd_classes(sys.argv[2])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'exact':
        cmd_exact(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'normal':
        cmd_normal(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) >= 3 and sys.argv[1] == 'invariants':
        cmd_invariants(sys.argv[2])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'dyads':
        cmd_dyads(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) >= 6 and sys.argv[1] == 'jacobian-geometry':
        jacobian(*[[float(x) for x in arg.split(',')] for arg in sys.argv[2:5]], sys.argv[5])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'jacobian':
        cmd_jacobian(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) >= 4 and sys.argv[1] == 'mobius':
        cmd_mobius(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'mobius-geometry':
        print_mobius('geometry', mobius_summary(*[[float(x) for x in arg.split(',')] for arg in sys.argv[2:5]], 100))
    elif len(sys.argv) >= 3 and sys.argv[1] == 'mobius-all':
        cmd_mobius_all(sys.argv[2])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'cubic':
        report_built(f"cubic motion polynomial, seed {sys.argv[2]}, order {sys.argv[3]}", *cubic_loop(sys.argv[2], sys.argv[3]),
                     sys.argv[4])
    elif len(sys.argv) >= 4 and sys.argv[1] == 'waldron':
        report_built(f"Waldron hybrid, seed {sys.argv[2]}", *waldron_loop(sys.argv[2]), sys.argv[3])
    elif len(sys.argv) >= 5 and sys.argv[1] == 't7-normal':
        cmd_t7_normal(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) >= 3 and sys.argv[1] == 't7-offsets':
        cmd_t7_offsets(sys.argv[2])
    elif len(sys.argv) >= 4 and sys.argv[1] == 't7-permutations':
        cmd_t7_permutations(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 4 and sys.argv[1] == 't7-signs':
        cmd_t7_signs(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 4 and sys.argv[1] == 't7-triad-relations':
        cmd_t7_triad_relations(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 3 and sys.argv[1] == 't7-flip':
        cmd_t7_flip(sys.argv[2])
    elif len(sys.argv) >= 3 and sys.argv[1] == 'b8-conditions':
        cmd_b8_conditions(sys.argv[2])
    elif len(sys.argv) >= 4 and sys.argv[1] == 'b8-count':
        cmd_b8_count(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 7 and sys.argv[1] == 'b8-build':
        cmd_b8_build(*sys.argv[2:7])
    elif len(sys.argv) >= 6 and sys.argv[1] == 'b8-build10':
        cmd_b8_build10(*sys.argv[2:6])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'near':
        cmd_near(*sys.argv[2:5])
    elif len(sys.argv) >= 5 and sys.argv[1] == 'locked-bennett':
        cmd_locked_bennett(*sys.argv[2:5])
    elif len(sys.argv) >= 6 and sys.argv[1] == 'triad-reorder':
        cmd_triad_reorder(*sys.argv[2:6])
    else:
        sys.exit(__doc__)
