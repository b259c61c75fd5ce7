"""Reference numbers for rtpipe's rotor aerodynamics, from rotorpy itself.

Run from anywhere:  python3 crates/flight/tests/data/aero/rotorpy_compare.py
(needs `pip install rotorpy`; written against rotorpy 3.0.0). It reads the
built-in racer5 preset's body and rotors and vehicle.toml's [aero] table,
builds the same vehicle in rotorpy (its `Multirotor`
with aero on; body.drag_linear and body.drag_angular, which rotorpy does not
have, are left out on both sides) and writes, next to this file:

- wrench.csv: rotorpy's aerodynamic force and moment (body frame; its wrench
  with aero on minus with aero off) at 40 seeded random states;
- step.csv, sine.csv: the open-loop response over 1 s to a step gust and a
  sinusoidal gust, every rotor commanded at the hover speed (no controller),
  the wind held over 1 ms steps as rtpipe's co-simulation holds it.

crates/flight/tests/aero.rs holds rtpipe's plant to these numbers.
"""
import csv
import pathlib
import tomllib

import numpy as np
from rotorpy.vehicles.multirotor import Multirotor
from scipy.spatial.transform import Rotation

HERE = pathlib.Path(__file__).resolve().parent
PRESET = HERE.parents[2] / "presets" / "racer5.toml"
AERO = HERE / "vehicle.toml"
DT = 1e-3
SAMPLE_EVERY = 10  # steps: a row every 10 ms
ALTITUDE = 10.0


def quad_params(p):
    a = p["aero"]
    h = a["rotor_height_m"]
    rotors = p["rotors"]
    spin = {"cw": 1.0, "ccw": -1.0}  # rtpipe's reaction sign = rotorpy's direction
    return {
        "mass": p["body"]["mass_kg"],
        "Ixx": p["body"]["inertia_kg_m2"][0],
        "Iyy": p["body"]["inertia_kg_m2"][1],
        "Izz": p["body"]["inertia_kg_m2"][2],
        "Ixy": 0.0, "Ixz": 0.0, "Iyz": 0.0,
        "num_rotors": 4,
        "rotor_pos": {f"r{i + 1}": np.array([x, y, h]) for i, (x, y) in enumerate(rotors["positions_m"])},
        "rotor_directions": np.array([spin[s] for s in rotors["spin"]]),
        "rI": np.zeros(3),
        "c_Dx": a["parasitic_drag"][0], "c_Dy": a["parasitic_drag"][1], "c_Dz": a["parasitic_drag"][2],
        "k_eta": rotors["k_f"], "k_m": rotors["k_m"],
        "k_d": a["rotor_drag"], "k_z": a["induced_inflow"],
        "k_h": a["translational_lift"], "k_flap": a["flapping"],
        "tau_m": rotors["time_constant_s"],
        "rotor_speed_min": 0.0, "rotor_speed_max": rotors["omega_max_rad_s"],
        "motor_noise_std": 0.0,
    }


def vehicle(qp, aero):
    tight = {"method": "RK45", "rtol": 1e-10, "atol": 1e-12}
    return Multirotor(qp, aero=aero, enable_ground=False, integrator_kwargs=tight)


def write(name, header, rows):
    with open(HERE / name, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        for r in rows:
            w.writerow([f"{v:.12e}" for v in r])


def wrench_rows(qp, n=40, seed=7):
    on, off = vehicle(qp, True), vehicle(qp, False)
    rng = np.random.default_rng(seed)
    w_max = qp["rotor_speed_max"]
    rows = []
    for _ in range(n):
        rate = rng.normal(0.0, 3.0, 3)
        omega = rng.uniform(0.2 * w_max, 0.9 * w_max, 4)
        air = rng.normal(0.0, 4.0, 3)
        f1, m1 = on.compute_body_wrench(rate, omega, air)
        f0, m0 = off.compute_body_wrench(rate, omega, air)
        rows.append([*rate, *omega, *air, *(f1 - f0), *(m1 - m0)])
    return rows


def gusts():
    step = lambda t: np.array([3.0, 2.0, 0.5]) if t >= 0.1 else np.zeros(3)
    sine = lambda t: np.array([
        2.0 * np.sin(2 * np.pi * 2.0 * t),
        1.5 * np.sin(2 * np.pi * 3.0 * t + 0.5),
        0.5 * np.sin(2 * np.pi * 1.0 * t),
    ])
    return {"step.csv": step, "sine.csv": sine}


def open_loop(qp, wind):
    quad = vehicle(qp, True)
    hover = np.sqrt(qp["mass"] * quad.g / (4 * qp["k_eta"]))
    state = {"x": np.array([0.0, 0.0, ALTITUDE]), "v": np.zeros(3), "q": np.array([0.0, 0.0, 0.0, 1.0]),
             "w": np.zeros(3), "wind": np.zeros(3), "rotor_speeds": np.full(4, hover)}
    control = {"cmd_motor_speeds": np.full(4, hover)}
    rows = []
    for k in range(1001):
        t = k * DT
        if k % SAMPLE_EVERY == 0:
            yaw, pitch, roll = Rotation.from_quat(state["q"]).as_euler("ZYX")
            rows.append([t, roll, pitch, yaw, *state["w"], *state["v"], *state["x"]])
        state["wind"] = wind(t)
        state = quad.step(state, control, DT)
    return hover, rows


def main():
    p = tomllib.loads(PRESET.read_text())
    p["aero"] = tomllib.loads(AERO.read_text())["aero"]
    qp = quad_params(p)
    write("wrench.csv",
          ["p", "q", "r", "w1", "w2", "w3", "w4", "ax", "ay", "az", "fx", "fy", "fz", "mx", "my", "mz"],
          wrench_rows(qp))
    for name, wind in gusts().items():
        hover, rows = open_loop(qp, wind)
        write(name, ["t", "roll", "pitch", "yaw", "p", "q", "r", "vx", "vy", "vz", "x", "y", "z"], rows)
        last = rows[-1]
        print(f"{name}: hover {hover:.3f} rad/s; at 1 s roll {np.degrees(last[1]):.3f}°, "
              f"pitch {np.degrees(last[2]):.3f}°, v ({last[7]:.3f}, {last[8]:.3f}, {last[9]:.3f}) m/s")


if __name__ == "__main__":
    main()
