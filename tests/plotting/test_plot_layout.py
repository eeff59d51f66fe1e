"""The layout of rotor's figures: legends in a corner their lines leave free, no line hidden
under another, speeds written as they are (no offset), whole cycles on cycle axes, the
angle labels of a polar diagram apart, a logic analyser's channel drawn as levels.

The checks here are the test's own (each line sampled every pixel), not the placing code's."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

import rotor
from rotor.plotting.common import CORNERS, cycle_axis, place_legend, speed_axis
from rotor.plotting.logs import plot_reading


def _samples_px(ax):
    """Every line of ``ax`` sampled about every pixel along its path, in display coordinates."""
    out = []
    for line in ax.get_lines():
        xy = line.get_transform().transform(np.asarray(line.get_xydata(), dtype=float))
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if len(xy) < 2:
            out.append(xy)
            continue
        seg = np.diff(xy, axis=0)
        n = np.maximum(1, np.ceil(np.hypot(seg[:, 0], seg[:, 1])).astype(int))
        n = np.minimum(n, 2000)  # a segment across the whole figure: 2000 samples are enough
        s = np.concatenate([np.arange(k) / k for k in n])
        idx = np.repeat(np.arange(len(seg)), n)
        out.append(np.vstack([xy[idx] + seg[idx] * s[:, None], xy[-1:]]))
    return np.vstack(out) if out else np.zeros((0, 2))


def _touches(ax, legend, renderer):
    box = legend.get_window_extent(renderer)
    p = _samples_px(ax)
    inside = (p[:, 0] >= box.x0) & (p[:, 0] <= box.x1) & (p[:, 1] >= box.y0) & (p[:, 1] <= box.y1)
    return int(inside.sum())


def _legends_are_free(fig):
    """Every legend of ``fig`` touches no line, unless no corner of its axes is free."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    checked = 0
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None or legend.get_bbox_to_anchor().bounds != ax.bbox.bounds:
            continue  # none, or placed outside the axes
        checked += 1
        if _touches(ax, legend, renderer) == 0:
            continue
        kwargs = {"fontsize": legend.prop.get_size()}
        free = []
        for corner in CORNERS:
            trial = ax.legend(loc=corner, **kwargs)
            fig.canvas.draw()
            free.append(_touches(ax, trial, renderer) == 0)
        assert not any(free), f"{ax.get_title()!r}: the legend sits on a line though a corner is free"
    return checked


# --- the helpers ------------------------------------------------------------------


def test_a_legend_goes_to_the_corner_the_lines_leave_free():
    fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
    x = np.linspace(0, 1, 200)
    ax.plot(x, x**4, label="rises late")  # fills the upper right and the lower left
    ax.plot(x, 0 * x + 0.02, label="flat")
    legend = place_legend(ax)
    assert legend._loc == 2  # upper left: the only corner no line crosses
    assert _legends_are_free(fig) == 1
    plt.close(fig)


def test_a_segment_through_a_corner_counts_though_no_vertex_lies_there():
    fig, ax = plt.subplots(figsize=(6, 4), layout="constrained")
    ax.plot([0, 1], [0, 1], label="diagonal")  # two vertices, at the lower left and upper right
    ax.plot([0, 1], [1, 0.0], label="the other diagonal")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    place_legend(ax)
    fig.canvas.draw()
    assert _touches(ax, ax.get_legend(), fig.canvas.get_renderer()) == 0  # room made above the lines
    assert ax.get_ylim()[1] > 1.0
    plt.close(fig)


def test_speed_and_cycle_axes():
    fig, (plain_ax, ax) = plt.subplots(1, 2)
    for a in (plain_ax, ax):
        a.plot([1, 2, 3], 3000 + 0.01 * np.array([1, -1, 1.3]))
    speed_axis(ax)
    cycle_axis(ax)
    fig.canvas.draw()
    # matplotlib's own choice: "+3e3" over the ticks, half cycles
    assert plain_ax.yaxis.get_major_formatter().get_offset() != ""
    assert not all(float(t).is_integer() for t in plain_ax.get_xticks())
    assert ax.yaxis.get_major_formatter().get_offset() == ""
    assert all(float(t).is_integer() for t in ax.get_xticks())
    plt.close(fig)


# --- rotor's figures --------------------------------------------------------------


@pytest.fixture(scope="module")
def diesel_table():
    return rotor.crank_table(rotor.load_engine("4chn15"), step_deg=2)


def test_the_forces_plot_hides_no_line_under_another(diesel_table):
    """P_Σ and K = P_Σ/cos β nearly coincide: the one drawn later is dashed or narrower, so
    that the one under it shows (every line of the legend can be seen)."""
    ax = diesel_table.plot(which="forces")
    lines = [ln for ln in ax.get_lines() if not ln.get_label().startswith("_")]
    assert [ln.get_label() for ln in lines][:3] == ["$P_g$", "$P_j$", "$P_Σ$"]
    span = np.ptp(ax.get_ylim())
    pairs = 0
    for i, under in enumerate(lines):
        for over in lines[i + 1 :]:
            if np.max(np.abs(under.get_ydata() - over.get_ydata())) < 0.03 * span:
                pairs += 1
                assert over.get_linestyle() != "-" or over.get_linewidth() < 0.6 * under.get_linewidth(), (
                    under.get_label(),
                    over.get_label(),
                )
    assert pairs >= 1  # P_Σ and K
    assert _legends_are_free(ax.figure) == 1
    plt.close("all")


def test_the_engine_figures_keep_their_legends_off_the_lines(diesel_table):
    for which in ("forces", "torque"):
        ax = diesel_table.plot(which=which)
        _legends_are_free(ax.figure)
    plt.close("all")
    ss = rotor.steady_state(rotor.load_engine("4chn15"), rpm=1250)
    for kind in ("cycle", "torque"):
        ax = ss.plot(kind=kind)
        assert _legends_are_free(np.ravel(ax)[0].figure) >= 1
        plt.close("all")


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("log") / "full_load.txt"
    rotor.simulated_recording(path, "tue-single", rpm=3000, cycles=6)
    return rotor.analyze_log(path, "60-2", columns="time,pressure_v,encoder_v", compression_ratio=8.5, rod_ratio=0.3266)


def test_the_cycle_to_cycle_panel_writes_speeds_and_whole_cycles(recording):
    """The mean speeds of the cycles differ by ±0.01 rpm: the axis writes 3000.010, not
    "+3e3" above 0.010; the cycle axis has whole cycles only."""
    axes = recording.plot()
    fig = axes.ravel()[0].figure
    fig.canvas.draw()
    assert np.ptp(recording.mean_rpm) < 0.1
    for ax in fig.axes:
        if "rpm" in ax.get_ylabel():
            assert ax.yaxis.get_offset_text().get_text() == "", ax.get_title()
            labels = [t.get_text().replace("−", "-") for t in ax.get_yticklabels() if t.get_text()]
            assert all(abs(float(s)) > 100 for s in labels), labels  # whole speeds, not their offsets
        if ax.get_xlabel().startswith("cycle ("):
            lo, hi = ax.get_xlim()
            shown = [t for t in ax.get_xticks() if lo <= t <= hi]
            assert shown and all(float(t).is_integer() for t in shown), shown
    assert _legends_are_free(fig) >= 1
    plt.close("all")


def test_the_big_end_polar_diagram_writes_its_angles_apart():
    loads = rotor.bearing_loads(rotor.load_engine("4chn15"), step_deg=2)
    for draw in (loads.plot_big_end, loads.plot_crank_pin, loads.plot_main_journal):
        ax = draw()
        fig = ax.figure
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        labels = [t for t in ax.texts if t.get_text()]
        assert len(labels) >= 6
        written = sorted(a for t in labels for a in t.get_text().split(", "))
        assert written == sorted(f"{a:g}" for a in np.arange(0, 720, 60))  # every angle, once
        boxes = [t.get_window_extent(renderer) for t in labels]
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                assert not boxes[i].overlaps(boxes[j]), (labels[i].get_text(), labels[j].get_text())
        legend = ax.get_legend().get_window_extent(renderer)
        assert not any(b.overlaps(legend) for b in boxes)
        _legends_are_free(fig)
        plt.close(fig)


def test_a_logic_analyser_channel_is_drawn_as_levels():
    t = np.arange(40) * 1e-3
    level = (np.arange(40) % 2).astype(float)
    ax = plot_reading(t, level, t[1::2], {}, [], "capture", steps=True)
    assert "[V]" not in ax.get_ylabel() and "level" in ax.get_ylabel()
    assert list(ax.get_yticks()) == [0, 1]
    assert not any(" V" in text.get_text() for text in ax.get_legend().get_texts())
    analog = plot_reading(t, 2.5 * level, t[1::2], {"timed at": 1.25}, [], "sensor")
    assert analog.get_ylabel() == "signal [V]"
    assert any(text.get_text() == "timed at 1.25 V" for text in analog.get_legend().get_texts())
    plt.close("all")
