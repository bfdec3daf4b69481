"""The signature search's operators on hand-built populations (no physics involved).

Statistical checks use fixed seeds and tolerances of ~6 standard deviations, and
each is paired with the value a wrong rule would give, so the test can fail.
"""
import numpy as np
import pytest

from nbst.search import mirror_images
from nbst.search.ops import (BEST, CULL_SUBSUMED, CULL_WORST, INS_ADDED, INS_CULLED, INS_DISPLACED, INS_FALLBACK,
                             INS_SIG_LIMIT,
                             INS_WORST, NTAB, SIZE, crossover, cull_subsumed, insert, insert_initial, new_population,
                             pop_append, pop_remove, rng_uniform, seed_state, select_senate, select_uniform,
                             sig_count, uniform_velocity)

N = 6  # disks in the hand-built populations


def build(members, *, best=None, cap=64, n=N):
    """Population from (signature, cost) pairs; velocities encode the member's index."""
    pop = new_population(cap, n)
    for k, (s, c) in enumerate(members):
        pop_append(pop, np.full((n, 2), float(k)), float(c), np.int64(s))
    if best is not None:
        pop.state[BEST] = best
    else:
        pop.state[BEST] = int(np.argmin(pop.cost[:len(members)]))
    return pop


def scratch(n=N, cap=64):
    return np.empty(n + 2, np.int64), np.empty(cap, np.bool_)


def members(pop):
    size = pop.state[SIZE]
    return sorted((int(pop.sig[j]), float(pop.cost[j])) for j in range(size))


def check_table(pop):
    """The signature table agrees with the members."""
    size, ntab = pop.state[SIZE], pop.state[NTAB]
    sigs, counts = np.unique(pop.sig[:size], return_counts=True)
    tab = dict(zip(pop.tab_sig[:ntab].tolist(), pop.tab_count[:ntab].tolist()))
    assert tab == dict(zip(sigs.tolist(), counts.tolist()))


# --------------------------------------------------------------------------- selection

def test_senate_selection_frequencies():
    # order 1: signature 0b0001 x5 members, 0b0010 x1; order 2: 0b0011 x3; order 3: 0b0111 x1
    mem = [(0b0001, 10 + k) for k in range(5)] + [(0b0010, 20), (0b0011, 30), (0b0011, 31), (0b0011, 32),
                                                   (0b0111, 40)]
    pop = build(mem)
    rng = seed_state(1)
    so, sk = scratch()
    T = 30000
    picks = np.array([select_senate(pop, N, rng, -1, so, sk) for _ in range(T)])
    freq = np.bincount(picks, minlength=len(mem)) / T
    by_sig = {}
    for j, (s, _) in enumerate(mem):
        by_sig[s] = by_sig.get(s, 0.0) + freq[j]
    # Senate: each represented order 1/3, each signature of an order equally likely
    expect = {0b0001: 1 / 6, 0b0010: 1 / 6, 0b0011: 1 / 3, 0b0111: 1 / 3}
    for s, p in expect.items():
        assert abs(by_sig[s] - p) < 0.016, (bin(s), by_sig[s], p)  # sd <= 0.0028
    # members of one signature equally likely: 1/30 each for the five 0b0001 members
    assert np.all(np.abs(freq[:5] - 1 / 30) < 0.007)
    # a House-like (uniform over members) rule would give the lone order-3 member 0.1
    assert by_sig[0b0111] > 0.3


def test_second_parent_maximizes_union_and_is_senate_like():
    # first parent: signature 0b0011 (member 0). popcount(0b0011 | s2):
    # 0b0011 -> 2, 0b1100 -> 4, 0b1110 -> 4, 0b1000 -> 3, 0b0100 -> 3
    mem = [(0b0011, 1.0), (0b0011, 2.0), (0b1100, 3.0), (0b1100, 3.5), (0b1100, 3.7), (0b1110, 4.0),
           (0b1000, 5.0), (0b0100, 6.0)]
    pop = build(mem)
    rng = seed_state(2)
    so, sk = scratch()
    T = 20000
    picks = np.array([select_senate(pop, N, rng, 0, so, sk) for _ in range(T)])
    sig = np.array([s for s, _ in mem])[picks]
    assert set(np.unique(sig).tolist()) == {0b1100, 0b1110}
    # orders 2 and 3 are represented among the maximizers: 1/2 each (House-like: 3/4 vs 1/4)
    assert abs(np.mean(sig == 0b1110) - 0.5) < 0.025  # sd 0.0035
    assert not np.any(picks == 0)


def test_second_parent_never_the_first_itself():
    # everything maximizes (the first parent has every bit); the first parent is alone in its signature
    mem = [(0b111111, 1.0), (0b000001, 2.0), (0b000011, 3.0)]
    pop = build(mem)
    rng = seed_state(3)
    so, sk = scratch()
    picks = np.array([select_senate(pop, N, rng, 0, so, sk) for _ in range(3000)])
    assert not np.any(picks == 0)
    assert set(picks.tolist()) == {1, 2}
    # its own signature is allowed when another member holds it
    pop = build([(0b000011, 1.0), (0b000011, 2.0), (0b000001, 3.0)])
    picks = np.array([select_senate(pop, N, rng, 0, so, sk) for _ in range(3000)])
    assert set(picks.tolist()) == {1, 2}


def test_uniform_selection_variant_b():
    pop = build([(0b1, 1.0)] * 9 + [(0b111, 2.0)])
    rng = seed_state(4)
    picks = np.array([select_uniform(pop, rng, -1) for _ in range(20000)])
    assert abs(np.mean(picks == 9) - 0.1) < 0.015  # House-like, not Senate-like (1/2)
    picks = np.array([select_uniform(pop, rng, 3) for _ in range(5000)])
    assert not np.any(picks == 3) and set(picks.tolist()) == set(range(10)) - {3}


# --------------------------------------------------------------------------- crossover

@pytest.mark.parametrize("engineered", [True, False])
def test_crossover_genetic_engineering(engineered):
    v1 = np.ones((N, 2))
    v2 = 2.0 * np.ones((N, 2))
    v1[5] = v2[5] = 0.0  # disk 5 noncueable
    cue = np.arange(5, dtype=np.int64)
    s1, s2 = np.int64(0b000011), np.int64(0b000110)  # disk 0 only in p1, disk 2 only in p2, disk 1 in both
    rng = seed_state(5)
    out = np.empty((N, 2))
    T = 4000
    from2 = np.zeros(N)
    for _ in range(T):
        crossover(v1, v2, s1, s2, cue, engineered, rng, out)
        assert np.all(out[:, 0] == out[:, 1])
        from2 += out[:, 0] == 2.0
        assert out[5, 0] == 0.0 and out[5, 1] == 0.0
    f = from2 / T
    if engineered:
        assert f[0] == 0.0 and f[2] == 1.0
    else:
        assert abs(f[0] - 0.5) < 0.05 and abs(f[2] - 0.5) < 0.05
    for i in (1, 3, 4):  # both or neither parent acceptable: a coin
        assert abs(f[i] - 0.5) < 0.05  # sd 0.008


# --------------------------------------------------------------------------- insert

def ins(pop, sig, cost, p1=-1, p2=-1, *, elitism=True, sig_limit=10, pop_limit=200, hard_limit=400,
        cull=CULL_SUBSUMED, seed=0, n=N):
    best = pop.state[BEST]
    improvement = best < 0 or cost < pop.cost[best]
    child = np.full((n, 2), -1.0)
    return insert(pop, child, float(cost), np.int64(sig), p1, p2, improvement, elitism, sig_limit, pop_limit,
                  hard_limit, cull, n, seed_state(seed), np.empty(n + 2, np.int64))


def test_child_displaces_its_same_signature_parent():
    pop = build([(0b01, 1.0), (0b01, 5.0), (0b10, 7.0)])
    assert ins(pop, 0b01, 6.0, p1=1) == INS_DISPLACED
    assert members(pop) == [(0b01, 1.0), (0b01, 6.0), (0b10, 7.0)]  # a worse child still replaces a non-best parent
    assert pop.vel[1, 0, 0] == -1.0
    # different signature: added, parent kept
    assert ins(pop, 0b11, 9.0, p1=1) == INS_ADDED
    assert pop.state[SIZE] == 4
    check_table(pop)


def test_crossover_child_matching_both_parents_replaces_one_at_random():
    replaced = set()
    for seed in range(40):
        pop = build([(0b01, 1.0), (0b01, 5.0), (0b01, 6.0)])
        assert ins(pop, 0b01, 9.0, p1=1, p2=2, seed=seed) == INS_DISPLACED
        replaced.add(tuple(j for j in (1, 2) if pop.cost[j] == 9.0))
    assert replaced == {(1,), (2,)}


def test_elitism_protects_the_best_parent():
    pop = build([(0b01, 1.0), (0b10, 5.0)])
    assert ins(pop, 0b01, 2.0, p1=0) == INS_ADDED  # no improvement: best kept, child added
    assert members(pop) == [(0b01, 1.0), (0b01, 2.0), (0b10, 5.0)]
    assert ins(pop, 0b01, 0.5, p1=0) == INS_DISPLACED  # an improvement replaces it
    assert members(pop) == [(0b01, 0.5), (0b01, 2.0), (0b10, 5.0)]
    assert pop.cost[pop.state[BEST]] == 0.5
    # variant G: no elitism, the best parent is displaced by a worse child
    pop = build([(0b01, 1.0), (0b10, 5.0)])
    assert ins(pop, 0b01, 2.0, p1=0, elitism=False) == INS_DISPLACED
    assert members(pop) == [(0b01, 2.0), (0b10, 5.0)]


def test_elitism_never_deletes_the_best_under_random_inserts():
    rng = np.random.default_rng(6)
    pop = build([(0b000001, 50.0)])
    best = 50.0
    for t in range(3000):
        size = pop.state[SIZE]
        sig = int(rng.integers(1, 2**N))
        cost = float(rng.uniform(0, 100))
        p1 = int(rng.integers(size))
        ins(pop, sig, cost, p1=p1, sig_limit=3, pop_limit=20, hard_limit=25, seed=t)
        best = min(best, cost)
        size = pop.state[SIZE]
        assert pop.cost[pop.state[BEST]] == best
        assert np.min(pop.cost[:size]) == best
        assert size <= 25
    check_table(pop)


def test_hard_limit_fallback_deletes_the_worst_outside_the_best_signature():
    # over the hard limit with nothing subsumed (every member has order 1): the worst member
    # outside the best's signature goes (with elitism), else the worst of all
    mem = [(0b01, 1.0), (0b01, 90.0), (0b10, 5.0), (0b10, 7.0)]
    pop = build(mem, best=0)
    assert ins(pop, 0b100, 3.0, pop_limit=2, hard_limit=4) == INS_FALLBACK
    assert members(pop) == sorted([(0b01, 1.0), (0b01, 90.0), (0b10, 5.0), (0b100, 3.0)])
    pop = build(mem, best=0)
    assert ins(pop, 0b100, 3.0, pop_limit=2, hard_limit=4, elitism=False) == INS_FALLBACK
    assert members(pop) == sorted([(0b01, 1.0), (0b10, 5.0), (0b10, 7.0), (0b100, 3.0)])
    check_table(pop)


def test_per_signature_limit_deletes_the_worst_of_that_signature():
    mem = [(0b01, float(c)) for c in range(1, 11)] + [(0b10, 100.0)]
    pop = build(mem)
    assert ins(pop, 0b01, 5.5) == INS_SIG_LIMIT
    assert sig_count(pop, np.int64(0b01)) == 10
    assert (0b01, 10.0) not in members(pop) and (0b01, 5.5) in members(pop) and (0b10, 100.0) in members(pop)
    assert ins(pop, 0b01, 50.0) == INS_SIG_LIMIT  # the child itself is the worst
    assert (0b01, 50.0) not in members(pop) and sig_count(pop, np.int64(0b01)) == 10
    # ties: the worst-of-signature rule must skip the best (index 0, equal cost)
    pop = build([(0b01, 1.0)] * 3, best=0)
    pop.vel[0] = 42.0
    assert ins(pop, 0b01, 1.0, sig_limit=3) == INS_SIG_LIMIT
    assert pop.state[SIZE] == 3 and pop.vel[pop.state[BEST], 0, 0] == 42.0
    check_table(pop)


def test_culling_deletes_exactly_the_lowest_order_subsumed_set():
    mem = [(0b0111, 1.0),  # order 3
           (0b0011, 2.0), (0b1001, 3.0),  # order 2: 0b0011 subsumed by 0b0111; 0b1001 not (bit 3)
           (0b0001, 4.0), (0b0001, 4.5), (0b0100, 5.0),  # order 1, subsumed
           (0b10000, 6.0)]  # order 1, not subsumed (bit 4 is in no higher-order solution)
    pop = build(mem, best=0)
    so = np.empty(N + 2, np.int64)
    assert cull_subsumed(pop, N, True, so) == 3
    assert members(pop) == sorted([(0b0111, 1.0), (0b0011, 2.0), (0b1001, 3.0), (0b10000, 6.0)])
    check_table(pop)
    # next round: nothing of order 1 is subsumed, so the order-2 subsumed set goes
    assert cull_subsumed(pop, N, True, so) == 1
    assert members(pop) == sorted([(0b0111, 1.0), (0b1001, 3.0), (0b10000, 6.0)])
    assert cull_subsumed(pop, N, True, so) == 0
    # a member of order 1 subsumed by an order-2 one (not only by the top order) counts
    pop = build([(0b0111, 1.0), (0b1001, 3.0), (0b1000, 6.0), (0b10000, 7.0)], best=0)
    assert cull_subsumed(pop, N, True, so) == 1
    assert members(pop) == sorted([(0b0111, 1.0), (0b1001, 3.0), (0b10000, 7.0)])


def test_culling_exempts_the_best_signature():
    mem = [(0b0111, 3.0), (0b0001, 0.5), (0b0001, 4.0), (0b0100, 5.0)]
    pop = build(mem, best=1)
    so = np.empty(N + 2, np.int64)
    assert cull_subsumed(pop, N, True, so) == 1
    assert members(pop) == sorted([(0b0111, 3.0), (0b0001, 0.5), (0b0001, 4.0)])
    assert pop.cost[pop.state[BEST]] == 0.5
    pop = build(mem, best=1)
    assert cull_subsumed(pop, N, False, so) == 3  # variant G: no exemption


def test_population_limit_triggers_culling_in_insert():
    mem = [(0b0111, 1.0), (0b0001, 4.0), (0b0100, 5.0), (0b1000, 6.0)]
    pop = build(mem)
    assert ins(pop, 0b0011, 3.0, pop_limit=4) == INS_CULLED  # size 5 > 4: order-1 subsumed ones go
    assert members(pop) == sorted([(0b0111, 1.0), (0b0011, 3.0), (0b1000, 6.0)])
    assert ins(pop, 0b0010, 9.0, pop_limit=4) == INS_ADDED  # size 4: no culling
    check_table(pop)


def test_variant_f_deletes_the_worst_on_every_addition():
    pop = build([(0b01, 1.0), (0b10, 5.0), (0b11, 3.0)])
    assert ins(pop, 0b100, 2.0, cull=CULL_WORST) == INS_WORST
    assert members(pop) == sorted([(0b01, 1.0), (0b11, 3.0), (0b100, 2.0)])
    assert ins(pop, 0b100, 9.0, cull=CULL_WORST) == INS_WORST  # the child itself is the worst
    assert members(pop) == sorted([(0b01, 1.0), (0b11, 3.0), (0b100, 2.0)])


def test_insert_initial_and_remove_keep_the_table_and_best():
    pop = new_population(16, N)
    for k, (s, c) in enumerate([(0b1, 3.0), (0b1, 2.0), (0b1, 1.0), (0b10, 4.0)]):
        best = pop.state[BEST]
        imp = best < 0 or c < pop.cost[best]
        insert_initial(pop, np.zeros((N, 2)), c, np.int64(s), imp, True, 2, 200)
    assert members(pop) == sorted([(0b1, 2.0), (0b1, 1.0), (0b10, 4.0)])  # the worst 0b1 (3.0) went
    assert pop.cost[pop.state[BEST]] == 1.0
    j = int(np.flatnonzero(pop.cost[:3] == 2.0)[0])
    pop_remove(pop, j)  # the last member moves into slot j; best must follow it
    check_table(pop)
    assert pop.cost[pop.state[BEST]] == 1.0
    pop_remove(pop, pop.state[BEST])
    assert pop.state[BEST] == -1 and members(pop) == [(0b10, 4.0)]


# --------------------------------------------------------------------------- randomize

def test_uniform_randomize_end_points_are_uniform_in_the_box():
    images = mirror_images(5)
    assert len(images) == 61 and np.abs(images).sum(axis=1).max() == 5
    x0 = np.array([[100.0, 300.0]])
    radius = np.array([20.0])
    W, H, T = 800.0, 600.0, 5.0
    rng = seed_state(7)
    v = np.zeros((1, 2))
    ends = []
    bounces = []
    for _ in range(20000):
        uniform_velocity(x0, radius, W, H, T, images, 0, rng, v)
        e = x0[0] + v[0] * T
        k = np.floor((e - radius[0]) / np.array([W - 40, H - 40]))
        bounces.append(np.abs(k).sum())
        u = (e - radius[0]) - k * np.array([W - 40, H - 40])  # fold into [0, L)
        u = np.where(k % 2 == 0, u, np.array([W - 40, H - 40]) - u)
        ends.append(u + radius[0])
    ends = np.array(ends)
    assert np.all(ends[:, 0] >= 20 - 1e-9) and np.all(ends[:, 0] <= W - 20 + 1e-9)
    assert np.all(ends[:, 1] >= 20 - 1e-9) and np.all(ends[:, 1] <= H - 20 + 1e-9)
    hx = np.histogram(ends[:, 0], bins=10, range=(20, W - 20))[0] / len(ends)
    assert np.all(np.abs(hx - 0.1) < 0.015)  # sd 0.002
    assert max(bounces) == 5 and abs(np.mean(np.array(bounces) == 0) - 1 / 61) < 0.006


def test_rng_is_reproducible():
    a, b = seed_state(9), seed_state(9)
    xa = [rng_uniform(a) for _ in range(5)]
    xb = [rng_uniform(b) for _ in range(5)]
    assert xa == xb and len(set(xa)) == 5 and all(0 <= x < 1 for x in xa)


def test_popcount_matches_python():
    from nbst.search.ops import popcount
    rng = np.random.default_rng(10)
    for x in [0, 1, 0b1011, 2**62 + 5, 2**63 - 1, *rng.integers(0, 2**63, 200).tolist()]:
        assert popcount(np.int64(x)) == int(x).bit_count()


def test_random_number_kernels_have_their_distributions():
    """xoshiro256** against its reference output, and the derived draws' ranges and moments
    (thresholds at 6 standard errors over 200,000 draws)."""
    from nbst.search.ops import rng_int, rng_next, rng_normal

    # xoshiro256** from state (1, 2, 3, 4): the reference implementation's first outputs
    s = np.array([1, 2, 3, 4], np.uint64)
    assert [int(rng_next(s)) for _ in range(3)] == [11520, 0, 1509978240]
    rng = seed_state(5)
    T = 200_000
    u = np.array([rng_uniform(rng) for _ in range(T)])
    assert u.min() >= 0.0 and u.max() < 1.0 and abs(u.mean() - 0.5) < 6 * (1 / 12) ** 0.5 / T ** 0.5
    k = np.array([rng_int(rng, 7) for _ in range(T)])
    assert k.min() == 0 and k.max() == 6
    np.testing.assert_allclose(np.bincount(k) / T, 1 / 7, atol=6 * (1 / 7 * 6 / 7 / T) ** 0.5)
    z = np.array([rng_normal(rng) for _ in range(T)])
    assert abs(z.mean()) < 6 / T ** 0.5 and abs(z.var() - 1.0) < 6 * (2 / T) ** 0.5
    assert abs((np.abs(z) < 1.0).mean() - 0.682689) < 6 * (0.6827 * 0.3173 / T) ** 0.5
