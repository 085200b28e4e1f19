#!/usr/bin/env python3
"""Pinocchio (pip `pin`, installed by scripts/install-deps.sh into .cache/) re-checks a solved
motion from the files alone, with its default settings: spacetime-cli's Z-up URDF
(--urdf-z-up) loaded by pinocchio.buildModelFromUrdf, whose gravity is (0, 0, -9.81), and
motion.json's q, q-dot, q-ddot through pinocchio.rnea must give motion.json's torques at every
frame of the flight (no contact force). The Y-up URDF read the same way must not (its gravity
would pull along the scene's -Z): the check can fail.

usage: pinocchio_check.py SPACETIME_CLI SCENE.json WORKDIR PYTHON_PACKAGES"""
import json
import os
import site
import subprocess
import sys

cli, scene, work, packages = sys.argv[1:5]
os.makedirs(work, exist_ok=True)
site.addsitedir(packages)  # the cmeel packages' .pth files
try:
    import numpy as np
    import pinocchio as pin
except ImportError as e:
    sys.exit(f"FAIL: Pinocchio is not installed in {packages} (scripts/install-deps.sh installs it): {e}")


def solve(out, *flags):
    subprocess.run([cli, "solve", scene, "--out", out, "--quiet", "--rate", "200", *flags], check=True,
                   stdout=subprocess.DEVNULL)
    return json.load(open(os.path.join(out, "motion.json")))["characters"][0]


def worst_flight_error(urdf, motion):
    model = pin.buildModelFromUrdf(urdf)  # default settings: gravity (0, 0, -9.81)
    data = model.createData()
    joint = {model.names[j]: j for j in range(1, model.njoints)}
    frames = [f for f in range(len(motion["times"]))
              if all(max(abs(x) for x in c["force"][f]) == 0 for c in motion["contacts"])]
    assert len(frames) > 20, f"only {len(frames)} flight frames"
    scale = max(abs(t) for f in frames for t in motion["tau"][f]) + 1
    worst = 0
    for f in frames:
        q, v, a = np.zeros(model.nq), np.zeros(model.nv), np.zeros(model.nv)
        for k, name in enumerate(motion["dofs"]):
            j = model.joints[joint[name]]
            if j.nq == 2:  # a continuous joint: (cos, sin)
                q[j.idx_q:j.idx_q + 2] = [np.cos(motion["q"][f][k]), np.sin(motion["q"][f][k])]
            else:
                q[j.idx_q] = motion["q"][f][k]
            v[j.idx_v] = motion["qd"][f][k]
            a[j.idx_v] = motion["qdd"][f][k]
        tau = pin.rnea(model, data, q, v, a)
        for k, name in enumerate(motion["dofs"]):
            worst = max(worst, abs(tau[model.joints[joint[name]].idx_v] - motion["tau"][f][k]) / scale)
    return worst, len(frames)


z_up = solve(os.path.join(work, "z_up"), "--urdf-z-up")
error, frames = worst_flight_error(os.path.join(work, "z_up", z_up["name"] + ".urdf"), z_up)
print(f"Z-up URDF, Pinocchio {pin.__version__} with default gravity: worst torque error {error:.2e} "
      f"(relative to the largest) over {frames} flight frames")
y_up = solve(os.path.join(work, "y_up"))
wrong, _ = worst_flight_error(os.path.join(work, "y_up", y_up["name"] + ".urdf"), y_up)
print(f"the Y-up URDF read the same way: {wrong:.2e}")
if not error < 1e-9:
    sys.exit("FAIL: Pinocchio's torques on the Z-up URDF differ from motion.json's")
if not wrong > 1e-3:
    sys.exit("FAIL: the Y-up URDF agrees under -Z gravity: the check cannot tell the frames apart")
