"""The figure of README.md and of the documentation's home page: the three examples of the
README, drawn from what they compute.

Run from the repository root (about half a minute):

    .venv/bin/python docs/figures/readme_figure.py

It writes docs/figures/readme.png.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import rotor  # noqa: E402

OUT = Path(__file__).resolve().parent / "readme.png"


def main() -> None:
    engine = rotor.load_engine("4chn15")
    ss = rotor.steady_state(engine, rpm=1250)

    pattern = rotor.combustion_pattern(12, 4, imep_scale=[1, 1.1, 0.9, 1], misfires=[(6, 3)], cov=0.02, seed=1)
    mis = rotor.simulate(engine, cycles=12, load=rotor.PropellerLoad(1100, 1250), combustion=pattern)
    ident = rotor.identify(engine, mis, load=rotor.PropellerLoad(1100, 1250))

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "full_load.txt"
        rotor.simulated_recording(path, "tue-single", rpm=3000, cycles=6)
        a = rotor.analyze_log(
            path, "60-2", columns="time,pressure_v,encoder_v", compression_ratio=8.5, rod_ratio=0.3266
        )

    fig, ax = plt.subplots(1, 3, figsize=(13, 3.6), layout="constrained")

    theta = np.rad2deg(np.asarray(ss.theta))
    ax[0].plot(theta, np.asarray(ss.omega) * 30 / np.pi)
    ax[0].set(
        xlabel="crank angle [deg]",
        ylabel="speed [rpm]",
        title=f"1. steady state, 4chn15: δ = {float(ss.delta):.4f}",
        xticks=np.arange(0, 721, 180),
    )

    imep = np.asarray(ident.imep_pa) / 1e5
    cycles = np.arange(1, imep.shape[0] + 1)
    for c in range(imep.shape[1]):
        ax[1].plot(cycles, imep[:, c], "o-", ms=3, label=f"cylinder {c + 1}")
    for cycle, cyl in ident.misfires():
        ax[1].plot(cycle, imep[cycle - 1, cyl - 1], "rx", ms=10, mew=2)
    ax[1].set(xlabel="cycle", ylabel="IMEP from speed [bar]", title="2. a misfire found from speed")
    ax[1].legend(fontsize=7, loc="lower left")

    omega = np.asarray(a.omega)
    phi = np.linspace(0, 720, omega.shape[1], endpoint=False)
    for k in range(omega.shape[0]):
        ax[2].plot(phi, omega[k] * 30 / np.pi, lw=0.8)
    ax[2].set(
        xlabel="crank angle [deg]",
        ylabel="speed [rpm]",
        title="3. a 60-2 wheel log, tue-single, per cycle",
        xticks=np.arange(0, 721, 180),
    )
    fig.savefig(OUT, dpi=90)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
