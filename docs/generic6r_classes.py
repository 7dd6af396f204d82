#!/usr/bin/env python3
"""The structure classes of a 6R run's unclassified loops (docs/discovery-5r-6r.md,
"The generic 6R search's unclassified loops"). Python 3 standard library only.

  docs/generic6r_classes.py classes DB            # counts per class and rigid-residual band
  docs/generic6r_classes.py exact DB LOOPFARM JOB # the loops closing to round-off, a markdown table
  docs/generic6r_classes.py jacobian DB START LOOPFARM
      # singular values of the 6 x 6 closure Jacobian at the poses `loopfarm verify --theta0-deg T`
      # assembles on the loop's motion (T = 0, 30, ..., 330; verified, E_mean < 1e-15)
  docs/generic6r_classes.py jacobian-geometry A ALPHA_DEG D LOOPFARM
      # the same for a geometry given as comma lists, and the non-adjacent axis pairs whose
      # distance and angle stay the same (to 1e-9) in all those poses
  docs/generic6r_classes.py normal DB START LOOPFARM
      # a P9 loop: the direction n in which its cycle energy grows, over the ten parameters the
      # other eight conditions leave (kappa1, alpha1, alpha2, kappa2, alpha4, alpha5, a3, alpha3,
      # d1, d4): sqrt(E) of `loopfarm energy` with each moved by 1e-4, signs from pairs
  docs/generic6r_classes.py invariants DB
      # P9 loops closing to <= 1e-11: dyad invariants compared between the two dyads
  docs/generic6r_classes.py dyads SEED N LOOPFARM
      # N loops built from bennett_dyads' conditions (docs/families.md), each checked with
      # `loopfarm verify --theta0-deg T`, T = 0, 5, ..., 355, until one verifies

Classes, tested on every shift and reversal of the canonical writing, each equality to 1e-6
(lengths in L, twists in degrees / 57.3; k_i = |sin alpha_i| / a_i, Bennett's ratio; a link
equals another when a and the twist agree up to sign and pi):
  pair  links 1 = 3, 4 = 6, 2 = 5, k1 = k2, k4 = k5, every d = 0 (bennett_pair's pattern)
  P9    link 3 = link 6, k1 = k2, k4 = k5, d2 = d5 = 0, |d1| = |d3|, |d4| = |d6|
  T7    k1 = k2 = k3, k4 = k5 = k6, d2 = d3 = d5 = d6 = 0, |d1| = |d4|
  B8    k2 = k3, k5 = k6, d3 = d6 = 0
"""
import collections, json, math, re, sqlite3, subprocess, sys

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


def writings(a, al, d):
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
        if any(test(*w) for w in writings(a, al, d)):
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


# Rigid kinematics for the Jacobian: T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) (DESIGN.md).
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
    n = len(S)
    A = [[sum(S[i][k] * S[j][k] for k in range(6)) for j in range(n)] for i in range(n)]
    for _ in range(100):  # Jacobi eigenvalues of the Gram matrix
        if sum(A[i][j] ** 2 for i in range(n) for j in range(n) if i != j) < 1e-30:
            break
        for p in range(n):
            for q in range(p + 1, n):
                if abs(A[p][q]) < 1e-300:
                    continue
                t = 0.5 * math.atan2(2 * A[p][q], A[q][q] - A[p][p])
                c, s = math.cos(t), math.sin(t)
                for k in range(n):
                    A[k][p], A[k][q] = c * A[k][p] - s * A[k][q], s * A[k][p] + c * A[k][q]
                for k in range(n):
                    A[p][k], A[q][k] = c * A[p][k] - s * A[q][k], s * A[p][k] + c * A[q][k]
    return sorted(math.sqrt(max(0.0, A[i][i])) for i in range(n))


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


def p9_writing(a, al, d):
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
    A, AL, D = p9_writing(list(v[0:6]), list(v[6:12]), list(v[12:18]))
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
        w = p9_writing(list(r[6:12]), list(r[12:18]), list(r[18:24]))
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
    else:
        sys.exit(__doc__)
