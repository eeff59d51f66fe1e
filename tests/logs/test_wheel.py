"""Trigger wheels: gap detection on 60-2, 36-1 and 36-2 wheels through a coast-down
3000 → 500 rpm, a start from rest and a 30 % speed change; index wheels; clear errors."""

import numpy as np
import pytest

import rotor
from rotor import LogError
from rotor.logs.wheel import TWO_PI, ToothTrack


def coastdown_t_of_theta(w0=3000 / 30 * np.pi, w1=500 / 30 * np.pi, revs=200, fluct=0.15):
    """t(θ) of a coast-down with a per-revolution fluctuation of ±fluct at the lowest speed (1/ω² scaling)."""
    theta = np.linspace(0, TWO_PI * revs, revs * 720 + 1)
    a = (w0**2 - w1**2) / 2 / theta[-1]
    G = fluct * w1**2 * (np.cos(theta) - 1) / 2
    omega = np.sqrt(w0**2 - 2 * a * theta + 2 * G)
    inv = 1 / omega
    t = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(theta))])
    return lambda x: np.interp(x, theta, t), theta[-1]


def teeth(wheel, t_of, theta_end, start=0.37):
    """Edge times and true (tooth, rev) of a wheel whose first edge after the gap sits at θ = start."""
    w = rotor.parse_wheel(wheel)
    r = np.arange(-1, int(theta_end / TWO_PI) + 2)
    ang = start + TWO_PI * r[:, None] + w.pitch_rad * np.arange(w.edges_per_rev)[None, :]
    tooth = np.broadcast_to(np.arange(w.edges_per_rev), ang.shape).ravel()
    ang = ang.ravel()
    ok = (ang >= 0) & (ang <= theta_end)
    return t_of(ang[ok]), tooth[ok]


@pytest.mark.parametrize("spec", ["60-2", "36-1", "36-2"])
def test_coastdown_3000_to_500_rpm_every_edge_placed(spec):
    t_of, end = coastdown_t_of_theta()
    t, true_tooth = teeth(spec, t_of, end)
    track = rotor.locate_teeth(t, spec)
    np.testing.assert_array_equal(track.tooth, true_tooth)
    assert track.revolutions == 199
    w = rotor.parse_wheel(spec)
    assert track.gap_ratio == pytest.approx(w.missing + 1, rel=0.05)


@pytest.mark.parametrize("spec", ["60-2", "36-1"])
def test_start_from_rest(spec):
    # constant angular acceleration from rest (a start), 0 → 1500 rpm in 20 revolutions
    end = TWO_PI * 20
    alpha = (1500 / 30 * np.pi) ** 2 / (2 * end)
    t, true_tooth = teeth(spec, lambda x: np.sqrt(2 * x / alpha), end, start=0.05)
    track = rotor.locate_teeth(t[1:], spec)  # the very first edge is at rest (t = 0 at θ = 0.05 rad after rest)
    np.testing.assert_array_equal(track.tooth, true_tooth[1:])


def test_speed_changing_30_percent():
    end = TWO_PI * 50
    w0, w1 = 2000 / 30 * np.pi, 2600 / 30 * np.pi
    alpha = (w1**2 - w0**2) / (2 * end)
    t, true_tooth = teeth("60-2", lambda x: (np.sqrt(w0**2 + 2 * alpha * x) - w0) / alpha, end)
    track = rotor.locate_teeth(t, "60-2")
    np.testing.assert_array_equal(track.tooth, true_tooth)


def test_index_wheel():
    t_of, end = coastdown_t_of_theta(revs=20, w1=2000 / 30 * np.pi)
    t, true_tooth = teeth("36", t_of, end)
    index = t[true_tooth == 0] - 1e-5
    track = rotor.locate_teeth(t, "36", index_times=index)
    assert track.tooth[np.searchsorted(t, index[0])] == 0
    np.testing.assert_array_equal(track.tooth[track.tooth == 0], 0)
    assert np.all(np.diff(track.tooth[track.rev >= 0])[np.diff(track.rev[track.rev >= 0]) == 0] == 1)
    with pytest.raises(LogError, match="index"):
        rotor.locate_teeth(t, "36")


def test_missed_and_extra_edges_and_wrong_wheel_are_errors():
    t_of, end = coastdown_t_of_theta(revs=10, w1=2500 / 30 * np.pi)
    t, _ = teeth("60-2", t_of, end)
    with pytest.raises(
        LogError, match=r"between the gaps at t = .* tooth edges where a 60-2 wheel gives 58 \(a missed or extra edge"
    ):
        rotor.locate_teeth(np.delete(t, 300), "60-2")
    extra = np.sort(np.append(t, 0.5 * (t[300] + t[301])))
    with pytest.raises(LogError, match="60-2"):
        rotor.locate_teeth(extra, "60-2")
    with pytest.raises(LogError, match="36-1 wheel gives 35"):
        rotor.locate_teeth(t, "36-1")
    with pytest.raises(LogError, match="more than one revolution"):
        rotor.locate_teeth(t[:50], "60-2")
    t36, _ = teeth("36", t_of, end)
    with pytest.raises(LogError, match="no gap"):
        rotor.locate_teeth(t36, "36-1")
    with pytest.raises(LogError, match="N-M"):
        rotor.parse_wheel("sixty")


def test_tooth_errors_save_load_and_checks(tmp_path):
    e = np.deg2rad(np.linspace(-0.1, 0.1, 58))
    te = rotor.ToothErrors("60-2", e)
    assert abs(te.errors_rad.mean()) < 1e-15
    te.save(tmp_path / "w.json")
    back = rotor.ToothErrors.load(tmp_path / "w.json")
    np.testing.assert_allclose(back.errors_rad, te.errors_rad, atol=1e-16)
    assert back.wheel == "60-2"
    with pytest.raises(LogError, match="58"):
        rotor.ToothErrors("60-2", e[:40])
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(LogError, match="not a tooth-error file"):
        rotor.ToothErrors.load(tmp_path / "bad.json")


def test_steady_estimate_keeps_the_engine_orders_out():
    """At steady speed an engine fluctuation at orders 2 and 4 (0.3° of angle) is left to
    the engine, and the wheel's errors at the other orders come back."""
    rng = np.random.default_rng(3)
    w = rotor.Wheel(60, 2)
    err = np.deg2rad(rng.uniform(-0.2, 0.2, 58))
    revs = 80
    theta = np.linspace(0, TWO_PI * revs, revs * 360 + 1)
    omega0 = 2000 / 30 * np.pi
    disp = np.deg2rad(0.3) * np.sin(2 * theta) + np.deg2rad(0.2) * np.sin(4 * theta + 1)  # angle lead of the engine
    t_of = lambda x: np.interp(x, theta, (theta - disp) / omega0)  # noqa: E731
    ang = (0.2 + TWO_PI * np.arange(revs - 1)[:, None] + w.pitch_rad * np.arange(58)[None, :] + err).ravel()
    track = rotor.locate_teeth(t_of(ang), w)
    te = rotor.estimate_tooth_errors(track)
    assert set(te.engine_orders) >= {2, 4}
    phi = w.pitch_rad * np.arange(58)
    from rotor.logs.wheel import order_fit_matrix

    X = order_fit_matrix(phi, te.engine_orders)
    beta, *_ = np.linalg.lstsq(X, err, rcond=None)
    identifiable = err - X @ beta  # the wheel's errors less the orders given to the engine
    assert np.rad2deg(np.max(np.abs(te.errors_rad - identifiable))) < 0.02
    naive = rotor.estimate_tooth_errors(track, engine_orders=())
    assert np.rad2deg(np.max(np.abs(naive.errors_rad - (err - err.mean())))) > 0.2  # the engine taken for the wheel


def test_log_starting_right_at_the_gap():
    """The first edge is the first after a gap (its long period lies before the log): it
    is tooth 0 of revolution 0, the first reference, and revolutions count from it as
    for a log that starts a few teeth earlier."""
    t_of, end = coastdown_t_of_theta(revs=12, w1=2500 / 30 * np.pi)
    t, true_tooth = teeth("60-2", t_of, end)
    k = int(np.flatnonzero(true_tooth == 0)[1])  # the first edge after the second gap
    at_gap = rotor.locate_teeth(t[k:], "60-2")
    assert at_gap.tooth[0] == 0 and at_gap.rev[0] == 0
    assert at_gap.to_json_dict()["first_reference_time_s"] == t[k]
    earlier = rotor.locate_teeth(t[k - 5 :], "60-2")
    np.testing.assert_array_equal(earlier.rev[5:], at_gap.rev)
    np.testing.assert_array_equal(earlier.tooth[5:], at_gap.tooth)
    a = rotor.analyze_log(rotor.Log.from_arrays(tooth_time_s=t[k:]), "60-2", tdc_deg=10, firing=0, tooth_errors=None)
    b = rotor.analyze_log(
        rotor.Log.from_arrays(tooth_time_s=t[k - 5 :]), "60-2", tdc_deg=10, firing=0, tooth_errors=None
    )
    np.testing.assert_allclose(a.t_start_s, b.t_start_s[: a.cycles], rtol=0, atol=1e-6)  # --firing 0 means one thing


def test_firing_orders():
    from rotor.logs.wheel import firing_orders

    assert firing_orders(4, 4, 60) == tuple(range(2, 30, 2))
    assert firing_orders(6, 4, 60) == tuple(range(3, 30, 3))
    assert firing_orders(3, 4, 60) == tuple(range(3, 30, 3))  # firing order 1.5: its whole multiples
    assert firing_orders(1, 4, 60) == firing_orders(2, 4, 60) == firing_orders(1, 2, 60) == ()
    assert firing_orders(2, 2, 36) == tuple(range(2, 18, 2))
    with pytest.raises(LogError, match="cylinders"):
        firing_orders(0, 4, 60)


@pytest.mark.parametrize(
    "content,match",
    [
        ('{"wheel": "60-2", "errors_rad": "x"}', r"t\.json: 'errors_rad' must be a list of finite numbers"),
        ('{"wheel": "60-2", "errors_rad": [0.0, 0.1]}', r"t\.json: 'errors_rad' has 2 values; a 60-2 wheel has 58"),
        ('{"wheel": "sixty", "errors_rad": []}', r"t\.json: 'wheel'"),
        ('{"wheel": "60-2", "errors_rad": [' + ",".join(["0"] * 57) + ", NaN]}", r"t\.json: 'errors_rad'"),
        (
            '{"wheel": "60-2", "errors_rad": [' + ",".join(["0"] * 58) + '], "revolutions": "many"}',
            r"t\.json: 'revolutions'",
        ),
    ],
)
def test_tooth_error_file_errors_name_file_and_key(tmp_path, content, match):
    (tmp_path / "t.json").write_text(content)
    with pytest.raises(LogError, match=match):
        rotor.ToothErrors.load(tmp_path / "t.json")


def test_tooth_errors_save_names_the_target(tmp_path):
    te = rotor.ToothErrors("60-2", np.zeros(58))
    target = tmp_path / "no" / "such" / "t.json"
    with pytest.raises(LogError, match=rf"^{target}: cannot write the tooth errors: no folder"):
        te.save(target)
    assert not (tmp_path / "no").exists()


def test_tooth_errors_fitted_matrix_free_equal_the_direct_fit():
    from rotor.logs import wheel as W

    w = rotor.parse_wheel("60-2")
    rng = np.random.default_rng(2)
    err = np.deg2rad(rng.normal(0.0, 0.2, w.edges_per_rev))
    R = 8
    tooth = np.tile(np.arange(w.edges_per_rev), R + 1)
    rev = np.repeat(np.arange(R + 1), w.edges_per_rev)
    phi = 2 * np.pi * rev + w.tooth_angles_rad[tooth] + err[tooth]
    t = (phi + 0.02 * np.sin(2 * phi)) / (2 * np.pi * 25)  # an engine's order 2 on top
    track = ToothTrack(t, tooth, rev, w)
    direct = rotor.estimate_tooth_errors(track, engine_orders=(1, 2, 3))
    old_cells = W.FIT_MATRIX_CELLS
    try:
        W.FIT_MATRIX_CELLS = 0  # every fit by FFTs
        by_fft = rotor.estimate_tooth_errors(track, engine_orders=(1, 2, 3))
        auto_fft = rotor.estimate_tooth_errors(track)
    finally:
        W.FIT_MATRIX_CELLS = old_cells
    np.testing.assert_allclose(by_fft.errors_rad, direct.errors_rad, atol=1e-12)
    auto = rotor.estimate_tooth_errors(track)
    assert auto_fft.engine_orders == auto.engine_orders
    np.testing.assert_allclose(auto_fft.errors_rad, auto.errors_rad, atol=1e-12)


def test_tooth_errors_of_a_wheel_of_100000_positions_in_seconds():
    import time

    w = rotor.parse_wheel("100000-2")
    E, R = w.edges_per_rev, 4
    tooth = np.tile(np.arange(E), R + 1)
    rev = np.repeat(np.arange(R + 1), E)
    t = (2 * np.pi * rev + w.tooth_angles_rad[tooth]) / (2 * np.pi * 50)
    t0 = time.perf_counter()
    te = rotor.estimate_tooth_errors(ToothTrack(t, tooth, rev, w))
    assert time.perf_counter() - t0 < 20  # about a second here; the direct fit took minutes
    assert np.max(np.abs(te.errors_rad)) < 1e-9  # a perfect wheel
