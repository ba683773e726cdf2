"""odo-gap: diagnose the sim-to-real gap of an odometry robot (DESIGN.md s. 6).

Reads recorded data only (candump logs of the sensor frames, decoded with can/odometry.dbc, plus a
ground-truth pose CSV, UMBmark return errors, or the linkage encoders alone), drives the nominal
model with the recorded wheel counts and asks which catalog effect explains what truth shows.
"""
