"""Seed 001 first and second phases: weights against eqs. 5-7 by hand, a one-object world
where the target is trivially identifiable, legality of the layered graph, scoring,
reproducibility, and bad input leaving the filter untouched."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import InputError, NonFiniteError, ShapeError
from models.pathrecovery import (
    CameraNetwork,
    FilterConfig,
    KBestLists,
    ParticleState,
    PathParticles,
    correct_states,
    init,
    kbest_score,
    legal_transitions,
    make_model,
    manhattan_grid,
    observation_support,
    path_score,
    recover_path,
    run_filter,
    simulate_scene,
    step,
)


def network_from_undirected(n, und, gaps=None, p_self=0.5, name="test"):
    """Equal-probability neighbours, self loop p_self; ``gaps`` maps (a, b) -> mean."""
    gaps = gaps or {}
    src, dst, gap = [], [], []
    for a, b in und:
        g = gaps.get((a, b), gaps.get((b, a), 0.0))
        src += [a, b]
        dst += [b, a]
        gap += [g, g]
    src += list(range(n))
    dst += list(range(n))
    gap += [0.0] * n
    src, dst, gap = np.array(src), np.array(dst), np.array(gap)
    order = np.lexsort((dst, src))
    src, dst, gap = src[order], dst[order], gap[order]
    deg = np.bincount(src, minlength=n) - 1
    probs = np.where(src == dst, np.where(deg[src] > 0, p_self, 1.0), (1 - p_self) / np.maximum(deg[src], 1))
    indptr = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=n))])
    ang = 2 * np.pi * np.arange(n) / n
    return CameraNetwork(indptr, dst, probs, gap, np.stack([np.cos(ang), np.sin(ang)], 1), name=name)


@pytest.fixture(scope="module")
def ring():
    n = 6
    return network_from_undirected(n, [(i, (i + 1) % n) for i in range(n)], gaps={(2, 3): 3.0})


# ----------------------------------------------------------------------------- eqs. 5-7
def support_by_hand(alpha, beta, w, fx, fz, f0):
    def ps(a, b):
        return np.exp(-0.5 * np.sum((a - b) ** 2))  # Sigma = I
    return beta * (alpha * w + (1 - alpha) * ps(fx, fz)) + (1 - beta) * ps(f0, fz)


def test_observation_support_is_eq_6():
    net = network_from_undirected(2, [(0, 1)])
    f0 = np.array([0.2, -0.1])
    model = make_model(net, 0, f0, np.eye(2), FilterConfig(alpha=0.3, beta=0.7))
    rng = np.random.default_rng(0)
    fx, fz, w = rng.standard_normal((5, 2)), rng.standard_normal((5, 2)), rng.random(5)
    got = observation_support(model, fx, fz, w)
    want = [support_by_hand(0.3, 0.7, w[i], fx[i], fz[i], f0) for i in range(5)]
    assert np.allclose(got, want)


def isolated_world(faithful):
    """3 cameras with only their self loops: prediction and diffusion keep everyone put."""
    net = network_from_undirected(3, [])
    f0 = np.array([0.0, 0.0])
    cfg = FilterConfig(num_particles=5, k=10, faithful=faithful)
    model = make_model(net, 0, f0, np.eye(2), cfg)
    fA = np.array([1.0, 0.5])
    particles = PathParticles(
        cam=np.array([0, 0, 1, 2, 2]),
        ta=np.array([0, 0, 0, 3, 0]),
        src=np.array([0, 0, 1, 2, 2]),
        feat=np.array([f0, fA, f0, f0, f0]),
        raw=np.array([0.9, 0.9, 0.9, 0.3, 0.9]),
    )
    state = ParticleState(particles, np.full(5, -np.log(5)))
    obs_cam = np.array([0, 0, 1])
    obs_feat = np.array([fA + 0.1, [0.1, 0.0], [2.0, 2.0]])
    return model, state, obs_cam, obs_feat


@pytest.mark.parametrize("faithful", [False, True])
def test_step_weights_by_hand(faithful):
    model, state, obs_cam, obs_feat = isolated_world(faithful)
    cfg = model.config
    _, info = step(np.random.default_rng(0), model, state, obs_cam, obs_feat, obs_offset=100)
    # by hand: W^p = 1 (self loop only); the hidden particle stays hidden (ta 3 -> 2)
    w = np.zeros(5)
    assoc = np.full(5, -1)
    for i in (0, 1, 2):
        cands = [j for j in range(3) if obs_cam[j] == state.particles.cam[i]]
        s = [support_by_hand(cfg.alpha, cfg.beta, 1.0, state.particles.feat[i], obs_feat[j], model.f0) for j in cands]
        w[i], assoc[i] = max(s), cands[int(np.argmax(s))]
    if faithful:
        weight = w.copy()
        weight[3] = state.particles.raw[3]  # stale
    else:
        weight = w.copy()
        weight[3] = cfg.hidden_likelihood
        weight = weight**cfg.sharpness
    weight = weight / weight.sum()
    want = {}
    for i in (0, 1, 2):
        key = ("v", 100 + assoc[i])
        want[key] = max(want.get(key, 0), weight[i]) if faithful else want.get(key, 0) + weight[i]
    want[("h", 2)] = weight[3]
    got = {}
    for kind, cam, obs, mass, ta in zip(info.kind, info.cam, info.obs, info.mass, info.ta):
        if kind == 0:
            got[("v", obs)] = mass
        elif kind == 1:
            got[("h", cam)] = mass
            assert ta == 2
    assert got.keys() == want.keys()
    for key in want:
        assert got[key] == pytest.approx(want[key])
    # listed best first; the visible particle without observations (camera 2) is not listed
    assert np.all(np.diff(info.mass[info.kind >= 0]) <= 0)
    assert np.sum(info.kind >= 0) == len(want)


def test_initial_state():
    net = network_from_undirected(3, [(0, 1), (1, 2)])
    model = make_model(net, 1, np.array([1.0, 2.0]), np.eye(2), FilterConfig(num_particles=7))
    s = init(model)
    p = s.particles
    assert np.all(p.cam == 1) and np.all(p.ta == 0) and p.feat.shape == (7, 2)
    assert np.allclose(p.feat, [1.0, 2.0])
    np.testing.assert_allclose(np.exp(s.log_weights), 1 / 7)


# ----------------------------------------------------------------------------- one object
def test_single_object_is_tracked_through_gaps(ring):
    """With no one else in the world the target is trivially identifiable: the default
    recovers it at (nearly) every step, visible or hidden; the faithful reading's stale
    hidden weights push hidden states above the visible target in the first phase."""
    tops, phase2, faithful_tops, hidden_steps = [], [], [], 0
    for seed in range(4):
        scene = simulate_scene(seed, ring, num_objects=1, num_timesteps=80, cm=None, spread=1.0)
        truth = scene.true_obs[1:]
        hidden_steps += np.sum(truth < 0)
        model = make_model(ring, scene.c0, scene.f0, scene.sigma, FilterConfig(num_particles=100))
        lists = run_filter(10 + seed, model, scene.odb)
        path = recover_path(model, lists, scene.odb.feat, k=7)
        tops.append(kbest_score(lists.kind, lists.obs, truth, 1))
        phase2.append(path_score(path.kind, path.obs, truth).overall)
        fmodel = make_model(ring, scene.c0, scene.f0, scene.sigma, FilterConfig(num_particles=100, faithful=True))
        flists = run_filter(10 + seed, fmodel, scene.odb)
        faithful_tops.append(kbest_score(flists.kind, flists.obs, truth, 1))
    assert hidden_steps > 10  # the scenes do exercise the gap
    assert np.mean(tops) >= 0.95 and np.mean(phase2) >= 0.95
    assert np.mean(faithful_tops) < np.mean(tops) - 0.1


def test_no_gap_modelling_lists_no_hidden_state(ring):
    scene = simulate_scene(1, ring, num_objects=3, num_timesteps=40, cm=None, spread=1.0)
    model = make_model(ring, scene.c0, scene.f0, scene.sigma, FilterConfig(num_particles=50, gaps=False))
    lists = run_filter(0, model, scene.odb)
    assert not np.any(lists.kind == 1)
    path = recover_path(model, lists, scene.odb.feat, k=5)
    assert not np.any(path.kind == 1)


# ----------------------------------------------------------------------------- reproducible
@pytest.fixture(scope="module")
def small_scene():
    net = manhattan_grid(0, 4, 4)
    return simulate_scene(2, net, num_objects=400, num_timesteps=40, cm=0.2)


def test_same_seed_same_result(small_scene):
    sc = small_scene
    model = make_model(sc.network, sc.c0, sc.f0, sc.sigma, FilterConfig(num_particles=120))
    a = run_filter(5, model, sc.odb)
    b = run_filter(5, model, sc.odb)
    c = run_filter(6, model, sc.odb)
    for name in ("kind", "cam", "ta", "obs", "mass"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(a.mass, c.mass)
    assert np.all(a.num_tracked_cameras <= model.config.n_fc)


def test_recovered_path_is_legal(small_scene):
    sc = small_scene
    for faithful in (False, True):
        model = make_model(sc.network, sc.c0, sc.f0, sc.sigma, FilterConfig(num_particles=120, faithful=faithful))
        lists = run_filter(3, model, sc.odb)
        path = recover_path(model, lists, sc.odb.feat, k=7)
        kinds = np.concatenate([[0], path.kind])
        cams = np.concatenate([[sc.c0], path.cam])
        tas = np.concatenate([[0], path.ta])
        for t in range(1, kinds.size):
            if path.jumped[t - 1]:
                continue
            ok = legal_transitions(
                sc.network, kinds[t - 1 : t], cams[t - 1 : t], tas[t - 1 : t],
                kinds[t : t + 1], cams[t : t + 1], tas[t : t + 1], faithful=faithful,
            )
            assert ok[0, 0], t
        # the chosen state is one of the listed ones
        assert np.all((path.rank >= 0) & (path.rank < 7))


# ----------------------------------------------------------------------------- second phase
def test_legal_transitions_rules(ring):
    V, H = 0, 1
    # visible 2 -> visible 3 needs a one-step delay on the gap edge (mean 3: P(d=1) > 0)
    ok = legal_transitions(ring, [V], [2], [0], [V, V, V], [3, 2, 4], [0, 0, 0])
    assert ok.tolist() == [[True, True, False]]
    # visible 2 -> hidden (3, ta): faithful needs P(delay = ta + 1) > 0
    ok = legal_transitions(ring, [V], [2], [0], [H, H, H], [3, 3, 1], [1, 9, 1], faithful=True)
    assert ok.tolist() == [[True, False, False]]
    # hidden countdown: exact in the faithful reading, destination-only by default
    for faithful, want in ((True, [[True, False, False]]), (False, [[True, True, False]])):
        ok = legal_transitions(ring, [H], [3], [2], [H, H, H], [3, 3, 4], [1, 2, 1], faithful=faithful)
        assert ok.tolist() == want
    ok = legal_transitions(ring, [H, H], [3, 3], [1, 2], [V], [3], [0], faithful=True)
    assert ok.tolist() == [[True], [False]]
    # without gaps there is no hidden state
    ok = legal_transitions(ring, [V], [2], [0], [H], [3], [1], gaps=False)
    assert ok.tolist() == [[False]]


def hand_lists(rows):
    """KBestLists from rows of [(kind, cam, ta, obs, mass), ...] (k = 3)."""
    k = 3
    T = len(rows)
    kind = np.full((T, k), -1, dtype=np.int8)
    cam = np.full((T, k), -1)
    ta = np.zeros((T, k), dtype=np.int64)
    obs = np.full((T, k), -1)
    mass = np.zeros((T, k))
    for t, row in enumerate(rows):
        for j, (a, b, c, d, e) in enumerate(row):
            kind[t, j], cam[t, j], ta[t, j], obs[t, j], mass[t, j] = a, b, c, d, e
    return KBestLists(kind, cam, ta, obs, mass, np.zeros(T, dtype=np.int64), np.zeros(T))


@pytest.mark.parametrize("faithful", [False, True])
def test_dp_prefers_legal_lower_ranked_states(ring, faithful):
    model = make_model(ring, 0, np.zeros(2), np.eye(2), FilterConfig(faithful=faithful))
    feat = np.zeros((10, 2))
    lists = hand_lists(
        [
            [(0, 3, 0, 0, 0.6), (0, 1, 0, 1, 0.4)],  # 0 -> 3 is not an edge: rank 1 wins
            [(0, 4, 0, 2, 0.5), (0, 1, 0, 3, 0.3), (0, 2, 0, 4, 0.2)],
            [(0, 5, 0, 5, 0.7), (0, 2, 0, 6, 0.3)],
        ]
    )
    path = recover_path(model, lists, feat, k=3)
    assert path.rank.tolist() == [1, 1, 1]
    assert not path.jumped.any()


def test_dp_restarts_on_disconnection(ring):
    model = make_model(ring, 0, np.zeros(2), np.eye(2), FilterConfig(faithful=True))
    lists = hand_lists([[(0, 3, 0, 0, 0.6), (0, 4, 0, 1, 0.4)], [(0, 4, 0, 2, 0.9)]])
    path = recover_path(model, lists, np.zeros((5, 2)), k=3)
    assert path.jumped.tolist() == [True, False]
    assert path.rank.tolist() == [0, 0]


# ----------------------------------------------------------------------------- scoring
def test_scoring_rules():
    true_obs = np.array([5, -1, 7])
    kind = np.array([[0, 1], [0, 1], [1, 0]])
    obs = np.array([[5, -1], [9, -1], [-1, 8]])
    ok = correct_states(kind, obs, true_obs)
    assert ok.tolist() == [[True, False], [False, True], [False, False]]
    assert kbest_score(kind, obs, true_obs, 1) == pytest.approx(1 / 3)
    assert kbest_score(kind, obs, true_obs, 2) == pytest.approx(2 / 3)
    s = path_score(kind[:, 0], obs[:, 0], true_obs)
    assert s.overall == pytest.approx(1 / 3) and s.visible == pytest.approx(0.5) and s.hidden == 0.0
    assert np.isnan(path_score(np.array([0]), np.array([5]), np.array([5])).hidden)
    with pytest.raises(InputError):
        kbest_score(kind, obs, true_obs, 3)
    empty = np.zeros(0, dtype=np.int64)
    with pytest.raises(InputError, match="no steps"):  # not NaN with numpy's warning
        path_score(empty, empty, empty)
    with pytest.raises(InputError, match="no steps"):
        kbest_score(empty.reshape(0, 2), empty.reshape(0, 2), empty, 1)


# ----------------------------------------------------------------------------- bad input
def test_bad_observations_leave_the_state_untouched():
    model, state, obs_cam, obs_feat = isolated_world(False)
    before = {name: np.copy(getattr(state.particles, name)) for name in ("cam", "ta", "src", "feat", "raw")}
    before_lw = np.copy(state.log_weights)
    rng = np.random.default_rng(0)
    rng_state = rng.bit_generator.state
    bad = [
        (InputError, obs_cam[::-1], obs_feat),  # not sorted by camera
        (InputError, np.array([0, 0, 7]), obs_feat),  # no such camera
        (ShapeError, obs_cam, obs_feat[:, :1]),
        (ShapeError, obs_cam[:, None], obs_feat),
        (NonFiniteError, obs_cam, np.where(np.eye(3, 2) > 0, np.nan, obs_feat)),
        (InputError, obs_cam.astype(float), obs_feat),
    ]
    for err, cams, feats in bad:
        with pytest.raises(err):
            step(rng, model, state, cams, feats)
        for name, arr in before.items():
            assert np.array_equal(getattr(state.particles, name), arr)
        assert np.array_equal(state.log_weights, before_lw)
        assert rng.bit_generator.state == rng_state


def test_bad_model_and_config():
    net = network_from_undirected(3, [(0, 1)])
    with pytest.raises(InputError, match="c0"):
        make_model(net, 5, np.zeros(2), np.eye(2))
    with pytest.raises(InputError, match="symmetric positive definite"):
        make_model(net, 0, np.zeros(2), -np.eye(2))
    with pytest.raises(ShapeError):
        make_model(net, 0, np.zeros(2), np.eye(3))
    with pytest.raises(NonFiniteError):
        make_model(net, 0, np.array([np.nan, 0.0]), np.eye(2))
    # scipy's ValueError "array must not contain infs or NaNs" named no argument
    for bad, error in ((np.full((2, 2), np.nan), NonFiniteError),
                       (np.diag([np.inf, 1.0]), NonFiniteError),
                       ([["a", "b"], ["c", "d"]], InputError),
                       (np.eye(2) * (1 + 1j), InputError)):  # fmt: skip
        with pytest.raises(error, match="sigma"):
            make_model(net, 0, np.zeros(2), bad)
    for field, value in (("num_particles", 0), ("alpha", 1.5), ("hidden_likelihood", 0.0), ("k", 2.5)):
        with pytest.raises(InputError, match=field):
            make_model(net, 0, np.zeros(2), np.eye(2), FilterConfig(**{field: value}))


def test_run_filter_checks_every_step_first(small_scene):
    sc = small_scene
    model = make_model(sc.network, sc.c0, sc.f0, sc.sigma, FilterConfig(num_particles=50))
    feat = sc.odb.feat.copy()
    feat[-1, 0] = np.inf  # the very last step is bad
    with pytest.raises(NonFiniteError):
        run_filter(0, model, sc.odb._replace(feat=feat))
    with pytest.raises(ShapeError):
        recover_path(model, run_filter(0, model, sc.odb), sc.odb.feat[:, :1])


@pytest.mark.parametrize(("change", "needle"), [
    ({"f0": np.zeros(4) + 0j}, "f0 holds complex numbers"),
    ({"f0": ["a"] * 4}, "f0 is not an array of numbers"),
    ({"c0": True}, "c0 must be an int camera id, got True"),
    ({"network": None}, "network must be an instance of CameraNetwork, got NoneType"),
    ({"config": "a"}, "config must be an instance of FilterConfig, got str"),
])  # fmt: skip
def test_make_model_names_a_bad_argument(change, needle):
    """Complex features lost their imaginary parts, text raised numpy's ValueError, True
    was camera 1, and a network or config of another kind raised AttributeError."""
    from models.pathrecovery.simulate import manhattan_grid

    base = dict(network=manhattan_grid(3), c0=0, f0=np.zeros(4), sigma=np.eye(4))
    make_model(**base)
    with pytest.raises(InputError) as exc:
        make_model(**{**base, **change})
    assert needle in str(exc.value)
