"""The suite's processes compile with LLVM's optimisation off (tests/conftest.py); a user's
are compiled at XLA's default level. A process at the default level computes a steady
state, a misfire run on the grid, its identification and a run of the adaptive angle
method, and gets what this process gets: the same numbers to rounding (the adaptive run
within its accuracy), the same misfires.
A result that hung on the rounding of one expression (a firing window's border, a
threshold met exactly) would differ here."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT

WORK = """
import json
import numpy as np
import rotor

diesel = rotor.load_engine("4chn15")
pattern = rotor.combustion_pattern(10, 4, imep_scale=[1.0, 1.08, 0.92, 1.04], misfires=[(4, 2), (6, 4), (9, 1)])
run = rotor.simulate(diesel, rpm=1250.0, cycles=10, load=rotor.ConstantLoad(1000.0), combustion=pattern,
                     step_deg=3.0, method="grid", progress=False)
found = rotor.identify(diesel, run)
marine = rotor.load_engine("mwm6")
angle = rotor.simulate(marine, rpm=2000.0, cycles=2, load=rotor.PropellerLoad(900.0, 2000.0), method="angle",
                       progress=False)
RESULT = {
    "steady_omega": np.asarray(rotor.steady_state(diesel).omega).tolist(),
    "grid_omega": np.asarray(run.omega).tolist(),
    "scale": np.asarray(found.scale).tolist(),
    "misfires": [list(m) for m in found.misfires()],
    "angle_omega": np.asarray(angle.omega).tolist(),
}
"""


def test_the_default_code_generation_gives_the_suites_numbers():
    env = dict(os.environ)
    flags = [f for f in env.get("XLA_FLAGS", "").split() if "xla_backend_optimization_level" not in f]
    if len(flags) == len(env.get("XLA_FLAGS", "").split()):
        pytest.skip("this process compiles at XLA's default level already (ROTOR_SUITE_XLA_DEFAULT or XLA_FLAGS)")
    env["XLA_FLAGS"] = " ".join(flags)
    child = subprocess.run(
        [sys.executable, "-c", WORK + "print(json.dumps(RESULT))"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=env,
        timeout=600,
    )
    assert child.returncode == 0, child.stderr[-2000:]
    theirs = json.loads(child.stdout.strip().splitlines()[-1])
    space: dict = {}
    exec(WORK, space)
    ours = space["RESULT"]
    for key in ("steady_omega", "grid_omega"):
        np.testing.assert_allclose(theirs[key], ours[key], rtol=1e-11, atol=0, err_msg=key)
    # the adaptive method's steps follow its error estimate, which rounding moves: the two
    # runs agree within the accuracy the suite asks of it against DOP853 (tests/dynamics)
    np.testing.assert_allclose(theirs["angle_omega"], ours["angle_omega"], rtol=1e-6, atol=0)
    np.testing.assert_allclose(theirs["scale"], ours["scale"], rtol=0, atol=1e-8)
    assert theirs["misfires"] == ours["misfires"] == [[4, 2], [6, 4], [9, 1]]
