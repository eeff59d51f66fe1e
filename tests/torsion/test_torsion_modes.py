"""Torsional chains and their free vibration: the eigenproblem against openTorsion and the
textbook examples, Holzer's method against the eigenproblem, the engine's chain against the
rigid model, the Campbell diagram's orders, and bad inputs as one-line errors."""

import numpy as np
import pytest

import rotor
from rotor.torsion.campbell import engine_orders
from rotor.torsion.model import mass_inertias, throw_inertias
from rotor.torsion.modes import holzer_residual, modal_damping_matrix, mode_shapes, natural_frequencies

TWO_DISKS = ([211.4, 8.3], [9.775e6])  # openTorsion's test_shaft: 176.1 Hz
FRISWELL_971 = ([3.5e-3, 3.5e-3, 3.5e-3, 0.15, 0.05], [12e3, 12e3, 14e3, 10e3])  # Friswell et al., ex. 9.7.1
MWM = (
    [0.0170, 0.0090, 0.0467, 0.0327, 0.0467, 0.0467, 0.0327, 0.0487, 2.0750],
    [1.106e6, 1.631e6, 1.253e6, 1.253e6, 1.678e6, 1.253e6, 1.253e6, 1.976e6],
)  # openTorsion's ICE (MWM) example, after Mendes et al. (2008), Fig. 4


def _opentorsion_hz(inertias, stiffnesses):
    ot = pytest.importorskip("opentorsion")
    shafts = [ot.Shaft(i, i + 1, None, None, k=k) for i, k in enumerate(stiffnesses)]
    disks = [ot.Disk(i, J) for i, J in enumerate(inertias)]
    wn, _, _ = ot.Assembly(shafts, disk_elements=disks).modal_analysis()
    w = np.sort(np.asarray(wn))[::2]  # each mode comes as a ± pair
    return w[1:] / (2 * np.pi)  # without the rigid-body mode


@pytest.mark.parametrize("case", [TWO_DISKS, FRISWELL_971, MWM], ids=["two-disks", "friswell-9.7.1", "mwm"])
def test_natural_frequencies_agree_with_opentorsion(case):
    mine = np.asarray(natural_frequencies(rotor.TorsionalChain(*case)))
    theirs = _opentorsion_hz(*case)
    np.testing.assert_allclose(mine, theirs, rtol=1e-6, atol=0)
    # the check can fail: a change of 1e-4 in one inertia is seen
    J = list(case[0])
    J[0] *= 1.0001
    off = np.asarray(natural_frequencies(rotor.TorsionalChain(J, case[1])))
    assert np.max(np.abs(off / theirs - 1)) > 1e-6


def test_published_textbook_values():
    f2 = rotor.torsional_modes(rotor.TorsionalChain(*TWO_DISKS)).natural_frequencies_hz
    assert np.round(f2, 1).tolist() == [176.1]
    f5 = rotor.torsional_modes(rotor.TorsionalChain(*FRISWELL_971)).natural_frequencies_hz
    assert np.round(f5, 2).tolist() == [81.21, 141.21, 378.95, 536.36]


def test_two_disk_closed_form():
    (J1, J2), (k,) = TWO_DISKS
    expected = np.sqrt(k * (J1 + J2) / (J1 * J2)) / (2 * np.pi)
    modes = rotor.torsional_modes(rotor.TorsionalChain(*TWO_DISKS))
    assert modes.natural_frequencies_hz.shape == (1,)
    assert modes.natural_frequencies_hz[0] == pytest.approx(expected, rel=1e-12)
    # the two disks swing against each other, J1·φ1 = −J2·φ2, the light one by +1
    phi = modes.mode_shapes[0]
    assert phi[0] < 0 and phi[1] == pytest.approx(1.0)
    assert J1 * phi[0] == pytest.approx(-J2 * phi[1], rel=1e-12)


@pytest.mark.parametrize("case", [TWO_DISKS, FRISWELL_971, MWM], ids=["two-disks", "friswell-9.7.1", "mwm"])
def test_holzer_agrees_with_the_eigenproblem(case):
    chain = rotor.TorsionalChain(*case)
    eig = np.asarray(natural_frequencies(chain))
    hol = rotor.holzer_frequencies(chain)
    np.testing.assert_allclose(hol, eig, rtol=1e-9, atol=0)
    # the residual vanishes at the roots and not between them
    scale = np.abs(holzer_residual(chain, 0.5 * (eig[:-1] + eig[1:]))) if len(eig) > 1 else np.ones(1)
    assert np.all(np.abs(holzer_residual(chain, hol)) < 1e-6 * np.max(scale))


def test_holzer_on_a_long_random_chain_and_as_a_method():
    rng = np.random.default_rng(18)
    chain = rotor.TorsionalChain(rng.uniform(0.01, 0.1, 40), rng.uniform(1e5, 1e7, 39))
    np.testing.assert_allclose(rotor.holzer_frequencies(chain), natural_frequencies(chain), rtol=1e-9)
    a = rotor.torsional_modes(chain)
    b = rotor.torsional_modes(chain, method="holzer")
    assert b.method == "holzer"
    np.testing.assert_allclose(b.mode_shapes, a.mode_shapes, atol=1e-9)


def test_mode_shapes_are_orthogonal_and_normalised():
    chain = rotor.TorsionalChain(*MWM)
    phi = mode_shapes(chain)
    assert np.allclose(np.max(phi, axis=1), 1.0) and np.allclose(np.max(np.abs(phi), axis=1), 1.0)
    G = phi @ np.diag(MWM[0]) @ phi.T
    assert np.allclose(G - np.diag(np.diag(G)), 0, atol=1e-12 * np.max(G))
    assert np.allclose(phi @ np.asarray(MWM[0]), 0, atol=1e-12)  # no rigid-body share
    m = rotor.torsional_modes(chain)
    assert np.allclose(m.participation.sum(axis=1), 1) and np.allclose(m.strain_energy_share.sum(axis=1), 1)
    assert m.nodes(1) == [7]  # the one-node mode twists the shaft to the flywheel


def test_damped_modes():
    (J1, J2), (k,) = TWO_DISKS
    c = 500.0
    chain = rotor.TorsionalChain(*TWO_DISKS, relative_damping_Nms_per_rad=[c])
    m = rotor.torsional_modes(chain)
    J = J1 * J2 / (J1 + J2)
    zeta = c / (2 * np.sqrt(k * J))
    assert m.damping_ratios[0] == pytest.approx(zeta, rel=1e-9)
    assert m.damped_frequencies_hz[0] == pytest.approx(m.natural_frequencies_hz[0] * np.sqrt(1 - zeta**2), rel=1e-9)
    modal = rotor.TorsionalChain(*MWM, modal_damping_ratio=0.03)
    mm = rotor.torsional_modes(modal)
    np.testing.assert_allclose(mm.damping_ratios, 0.03, rtol=1e-8)
    assert np.allclose(np.asarray(modal_damping_matrix(modal)) @ np.ones(9), 0, atol=1e-9)  # rigid mode free
    assert rotor.torsional_modes(rotor.TorsionalChain(*MWM)).damping_ratios is None


def test_geometry_constructors():
    chain = rotor.TorsionalChain.from_shafts([1.0, 2.0], [0.5], [0.05], [0.02], shear_modulus_pa=80e9)
    assert float(chain.stiffnesses_Nm_per_rad[0]) == pytest.approx(80e9 * np.pi * (0.05**4 - 0.02**4) / 16, rel=1e-12)
    k = rotor.crank_throw_stiffness(
        journal_diameter_m=0.08,
        journal_length_m=0.04,
        pin_diameter_m=0.07,
        pin_length_m=0.035,
        web_thickness_m=0.025,
        web_width_m=0.12,
        crank_radius_m=0.0685,
    )
    Le = (0.04 + 0.8 * 0.025) + 0.75 * 0.035 * (0.08 / 0.07) ** 4 + 1.5 * 0.0685 * 0.08**4 / (0.025 * 0.12**3)
    assert k == pytest.approx(80e9 * np.pi * 0.08**4 / (32 * Le), rel=1e-12)
    assert 1e5 < k < 1e7  # the order of the MWM chain's sections


def test_engine_chain_is_the_rigid_model_split_into_masses():
    for name in ("mwm6", "tue-single"):
        e = rotor.load_engine(name)
        theta = np.linspace(0, 4 * np.pi, 37)
        total = np.asarray(mass_inertias(e, theta)).sum(axis=-1)
        np.testing.assert_allclose(total, np.asarray(rotor.reduced_inertia(e, theta)), rtol=1e-12)
        chain = rotor.torsional_chain(e)
        assert float(chain.total_inertia_kgm2) == pytest.approx(float(rotor.mean_reduced_inertia(e)), rel=1e-9)
        assert np.all(np.asarray(throw_inertias(e, theta))[:, chain.load_mass] == 0)


def test_mwm6_preset_is_the_published_chain():
    e = rotor.load_engine("mwm6")
    chain = rotor.torsional_chain(e)
    assert chain.throw_masses == (2, 3, 4, 5, 6, 7) and chain.load_mass == 8
    np.testing.assert_allclose(np.asarray(chain.inertias_kgm2)[:8], MWM[0][:8], rtol=2e-4)
    modes = rotor.torsional_modes(e)
    np.testing.assert_allclose(
        modes.natural_frequencies_hz, _opentorsion_hz(np.asarray(chain.inertias_kgm2), MWM[1]), rtol=1e-6
    )
    # within 0.1 % of the published chain's (the flywheel differs by 0.11 %)
    np.testing.assert_allclose(modes.natural_frequencies_hz, natural_frequencies(rotor.TorsionalChain(*MWM)), rtol=1e-3)
    # the reciprocating masses make each frequency breathe over the cycle
    assert np.all(modes.frequency_min_hz < modes.natural_frequencies_hz)
    assert np.all(modes.frequency_max_hz > modes.natural_frequencies_hz)
    assert 0.01 < modes.frequency_max_hz[0] / modes.frequency_min_hz[0] - 1 < 0.1


def test_tue_single_first_mode_is_the_measured_resonance():
    modes = rotor.torsional_modes(rotor.load_engine("tue-single"), rpm=3000)
    assert 4.5 <= modes.resonant_orders[0] <= 5.0
    assert modes.natural_frequencies_hz[0] == pytest.approx(237.5, abs=0.5)


def test_campbell_orders_and_critical_speeds():
    e = rotor.load_engine("mwm6")
    c = rotor.campbell(e, rpm=(600.0, 2600.0))
    assert c.major_orders == (3.0, 6.0, 9.0, 12.0)  # an even-firing inline six
    np.testing.assert_array_equal(c.orders, engine_orders(4))
    f1 = c.natural_frequencies_hz[0]
    crit = [s for s in c.critical_speeds if s["mode"] == 1 and s["order"] == 6.0]
    assert len(crit) == 1 and crit[0]["rpm"] == pytest.approx(60 * f1 / 6, rel=1e-12) and crit[0]["major"]
    assert crit[0]["relative_amplitude"] == pytest.approx(1.0, rel=1e-9)  # the one-node mode: all throws in phase
    assert all(600 <= s["rpm"] <= 2600 for s in c.critical_speeds)
    # the phase sum of a minor order is smaller; a single cylinder excites every order fully
    assert np.all(c.relative_amplitudes[0] <= 1 + 1e-12) and c.relative_amplitudes[0, 1] < 0.2
    single = rotor.campbell(rotor.load_engine("tue-single"), rpm=(1000.0, 4000.0))
    np.testing.assert_allclose(single.relative_amplitudes, 1.0)
    # a bare chain with its firing angles gives the same phase sums
    chain = rotor.torsional_chain(e)
    fa = np.rad2deg(np.asarray(e.firing_angles_rad))
    bare = rotor.campbell(chain, rpm=(600.0, 2600.0), firing_angles_deg=fa)
    np.testing.assert_allclose(bare.relative_amplitudes, c.relative_amplitudes, atol=1e-12)
    two = rotor.campbell(chain, rpm=np.linspace(100, 3000, 50), strokes=2)
    assert two.orders[0] == 1.0 and two.relative_amplitudes is None and len(two.rpm) == 50


BAD_CHAINS = [
    (
        "negative stiffness",
        dict(inertias_kgm2=[1.0, 2.0], stiffnesses_Nm_per_rad=[-5.0]),
        r"stiffnesses_Nm_per_rad.*positive",
    ),
    ("zero inertia", dict(inertias_kgm2=[1.0, 0.0], stiffnesses_Nm_per_rad=[5.0]), r"inertias_kgm2.*positive"),
    ("wrong lengths", dict(inertias_kgm2=[1.0, 2.0, 3.0], stiffnesses_Nm_per_rad=[5.0]), r"one stiffness per shaft"),
    ("one mass", dict(inertias_kgm2=[1.0], stiffnesses_Nm_per_rad=[]), r"two or more"),
    ("nan", dict(inertias_kgm2=[1.0, np.nan], stiffnesses_Nm_per_rad=[5.0]), r"finite"),
    (
        "throw outside",
        dict(inertias_kgm2=[1.0, 2.0], stiffnesses_Nm_per_rad=[5.0], throw_masses=[2]),
        r"throw_masses.*outside",
    ),
    ("load outside", dict(inertias_kgm2=[1.0, 2.0], stiffnesses_Nm_per_rad=[5.0], load_mass=5), r"load_mass"),
    (
        "damping length",
        dict(inertias_kgm2=[1.0, 2.0], stiffnesses_Nm_per_rad=[5.0], absolute_damping_Nms_per_rad=[1.0]),
        r"one value per mass",
    ),
    (
        "modal above 1",
        dict(inertias_kgm2=[1.0, 2.0], stiffnesses_Nm_per_rad=[5.0], modal_damping_ratio=1.5),
        r"below 1",
    ),
    ("names", dict(inertias_kgm2=[1.0, 2.0], stiffnesses_Nm_per_rad=[5.0], names=["a"]), r"one name per mass"),
]


@pytest.mark.parametrize("label,kwargs,pattern", BAD_CHAINS, ids=[b[0] for b in BAD_CHAINS])
def test_bad_chains_are_one_line_errors_naming_the_field(label, kwargs, pattern):
    with pytest.raises(rotor.EngineError, match=pattern) as err:
        rotor.TorsionalChain(**kwargs)
    assert "\n" not in str(err.value) and "TorsionalChain(" in str(err.value)


def test_bad_arguments():
    chain = rotor.TorsionalChain(*TWO_DISKS)
    with pytest.raises(TypeError, match="TorsionalChain or a rotor.Engine"):
        rotor.torsional_modes("mwm6")
    with pytest.raises(rotor.EngineError, match="method"):
        rotor.torsional_modes(chain, method="rayleigh")
    with pytest.raises(rotor.EngineError, match=r"no \[torsion\] table"):
        rotor.torsional_modes(rotor.load_engine("4chn15"))
    with pytest.raises(rotor.EngineError, match="speed range"):
        rotor.campbell(chain)
    with pytest.raises(rotor.EngineError, match="upper end"):
        rotor.campbell(chain, rpm=(2000.0, 1000.0))
    with pytest.raises(rotor.EngineError, match="firing_angles_deg"):
        rotor.campbell(chain, rpm=(1000.0, 2000.0), firing_angles_deg=[0.0])
    with pytest.raises(rotor.EngineError, match="bore must be smaller"):
        rotor.shaft_stiffness(0.1, 0.05, 0.06)


def _mwm6_data():
    import tomllib

    from rotor.engine.file import preset_path

    return tomllib.loads(preset_path("mwm6").read_text(encoding="utf-8"))


def test_torsion_table_mirrors_the_file():
    data = _mwm6_data()
    e = rotor.engine_from_dict(data)
    t = data["torsion"]
    np.testing.assert_array_equal(np.asarray(e.torsion.inertias_kgm2), t["inertias_kgm2"])
    np.testing.assert_array_equal(np.asarray(e.torsion.stiffnesses_Nm_per_rad), t["stiffnesses_Nm_per_rad"])
    assert list(e.torsion.throw_masses) == t["throw_masses"] and e.torsion.load_mass == t["load_mass"]
    assert list(e.torsion.names) == t["names"]
    # the table is optional, and the rigid model does not look at it
    del data["torsion"]
    rigid = rotor.engine_from_dict(data)
    assert rigid.torsion is None
    assert float(rotor.mean_reduced_inertia(rigid)) == float(rotor.mean_reduced_inertia(e))


BAD_TABLES = [
    ("unknown key", lambda t: t.update(stiffness=[1.0]), r"\[torsion\] stiffness: unknown key"),
    ("missing throws", lambda t: t.pop("throw_masses"), r"\[torsion\] throw_masses is missing"),
    ("throw outside", lambda t: t.update(throw_masses=[3, 4, 5, 6, 7, 10]), r"throw_masses.*mass 10 does not exist"),
    ("too few throws", lambda t: t.update(throw_masses=[3, 4, 5]), r"throw_masses.*6 crank throws"),
    ("negative stiffness", lambda t: t["stiffnesses_Nm_per_rad"].__setitem__(2, -1.0), r"stiffnesses_Nm_per_rad"),
    ("short stiffnesses", lambda t: t["stiffnesses_Nm_per_rad"].pop(), r"one stiffness per shaft section"),
    ("name not a string", lambda t: t["names"].__setitem__(0, 1), r"\[torsion\] names: item 1"),
    ("sum off", lambda t: t["inertias_kgm2"].__setitem__(8, 2.0750), r"sum to .* \[crankshaft\] inertia_kgm2"),
    ("load outside", lambda t: t.update(load_mass=12), r"load_mass = 12"),
    ("implausible", lambda t: t["stiffnesses_Nm_per_rad"].__setitem__(0, 1e15), r"plausible"),
]


@pytest.mark.parametrize("label,mutate,pattern", BAD_TABLES, ids=[b[0] for b in BAD_TABLES])
def test_bad_torsion_tables_are_one_line_errors(label, mutate, pattern):
    data = _mwm6_data()
    mutate(data["torsion"])
    with pytest.raises(ValueError, match=pattern) as err:
        rotor.engine_from_dict(data)
    assert "\n" not in str(err.value)


def test_two_cylinders_on_a_throw():
    """A V8: four throws, two cylinders each; the chain's throws carry both mechanisms."""
    e = rotor.load_engine("v8")
    table = rotor.Torsion(
        inertias_kgm2=[0.01, 0.03, 0.02, 0.02, 0.03, 0.18],
        stiffnesses_Nm_per_rad=[5e5, 8e5, 8e5, 8e5, 8e5],
        throw_masses=[2, 3, 4, 5],
    )
    v8 = e.replace(torsion=table)
    theta = np.linspace(0, 4 * np.pi, 25)
    np.testing.assert_allclose(
        np.asarray(mass_inertias(v8, theta)).sum(axis=-1), np.asarray(rotor.reduced_inertia(v8, theta)), rtol=1e-12
    )
    per_throw = np.asarray(throw_inertias(v8, theta))[:, 1:5]
    cyl = np.asarray(rotor.cylinder_inertia(v8, theta))
    np.testing.assert_allclose(per_throw[:, 0], cyl[:, 0] + cyl[:, 4], rtol=1e-12)
    c = rotor.campbell(v8, rpm=(800.0, 6000.0))
    assert c.major_orders == (4.0, 8.0, 12.0)  # eight cylinders firing every 90°
    with pytest.raises(rotor.EngineError, match="4 crank throws"):
        e.replace(torsion=rotor.Torsion(inertias_kgm2=[0.1, 0.2], stiffnesses_Nm_per_rad=[1e5], throw_masses=[1, 2]))
