"""An independent "reality" for odo-gap's blind check (issue 13, item 1).

A world written without host_sim's code or effect laws: its own rigid-body integrator and
physics step, its own planner and path controller driving from the robot's own dead reckoning,
its own effect laws (two or more per catalog effect) and out-of-catalog effects, a floor that is
never perfect, and sensors with their own rates, latencies and noise. README.md documents the
laws, their sources and ranges.

Interface (what odo-gap blind dispatches to; same signatures as gap/blind.py):

EFFECTS: catalog effect name -> the laws implemented for it
OUT_OF_CATALOG: names of the out-of-catalog effects
draw_case(rng, k) -> dict: case k's hidden key. Keys: case, world ("independent"), vehicle
    ("labmate" | "clapper" | "set"), kind ("none" | "single" | "pair" | "ooc"), effects (sorted
    names), laws ({effect: law}), params (catalog parameters "effect.param" where the law has a
    direct catalog equivalent), scope ({effect: "A" | "B" | "both" | "vehicle"}), visible
    ({effect: {"truth", "returns", "linkage": bool}}: where the effect can be seen at all), true
    (the laws' own parameters, mechanics, motor, encoder, background floor), robot (the nominal
    robot.json), tick_ms, controller, fidelity (physics step, truth rate/latency/jitter/noise and
    lever arm, return noise, CAN timing), plan (the runs: label, shape, segments, name).
simulate_case(case, real, seed) -> dict: writes the recorded data into the new folder `real`
    and returns extra key fields (events: bump hits with run, truck, wheel, x_mm, y_mm (floor
    frame, the truth's), t_s (robot clock, as the files are stamped), t_run_s, excess_mm;
    runs; link_clamps; imprint: per mode, how far the effect reaches that evidence against a
    no-effect twin (imprint.py); generation_s).
"""

from __future__ import annotations

from .cases import EFFECTS, OUT_OF_CATALOG, draw_case
from .simulate import simulate_case

__all__ = ["EFFECTS", "OUT_OF_CATALOG", "draw_case", "simulate_case"]
