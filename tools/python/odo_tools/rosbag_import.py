"""ROS 2 bags for odo-import (`odo-import ros2-bag`), read with the `rosbags` package (no ROS).

Wheels: sensor_msgs/msg/JointState on one topic, the two wheel joints named by the user; their
`position` (rad, running totals as a ros2_control joint state broadcaster publishes them) is
sampled on the robot's tick grid (linear interpolation: positions are continuous) and becomes
decoder counts with the robot's geometry. Truth (optional): nav_msgs/msg/Odometry or
geometry_msgs/msg/PoseStamped (motion capture) on one topic, sampled on the same grid; yaw from
the quaternion. Times are the messages' header stamps (the bag's receive time when a stamp is
zero). Errors name the bag and the topic.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .gap.errors import GapInputError

TRUTH_TYPES = ("nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped")


def _stamp(msg, t_bag_ns: int) -> float:
    st = msg.header.stamp
    ns = st.sec * 1_000_000_000 + st.nanosec
    return (ns if ns else t_bag_ns) * 1e-9


def read_bag(
    bag: Path, joint_topic: str, joints: tuple[str, str], truth_topic: str | None, tick_s: float
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray] | None]:
    """(ticks table, truth table or None) on the tick grid: role -> array (time s, left/right rad,
    x/y m, theta rad)."""
    from rosbags.highlevel import AnyReader

    try:
        reader = AnyReader([bag])
        reader.open()
    except Exception as e:  # rosbags raises its own errors for missing or damaged bags
        raise GapInputError(bag, f"cannot read as a ROS 2 bag: {e}") from None
    try:
        topics = {c.topic: c.msgtype for c in reader.connections}
        if joint_topic not in topics:
            raise GapInputError(
                bag, f"no topic {joint_topic} (has {', '.join(sorted(topics)) or 'none'})"
            )
        if topics[joint_topic] != "sensor_msgs/msg/JointState":
            raise GapInputError(bag, f"{joint_topic} is {topics[joint_topic]}, not JointState")
        if truth_topic is not None:
            if truth_topic not in topics:
                raise GapInputError(
                    bag, f"no topic {truth_topic} (has {', '.join(sorted(topics))})"
                )
            if topics[truth_topic] not in TRUTH_TYPES:
                raise GapInputError(
                    bag, f"{truth_topic} is {topics[truth_topic]}, not {' or '.join(TRUTH_TYPES)}"
                )
        jt, jl, jr = [], [], []
        tt, tx, ty, tth = [], [], [], []
        for con, t_ns, raw in reader.messages():
            if con.topic == joint_topic:
                m = reader.deserialize(raw, con.msgtype)
                names = list(m.name)
                try:
                    il, ir = names.index(joints[0]), names.index(joints[1])
                except ValueError:
                    missing = [j for j in joints if j not in names]
                    raise GapInputError(
                        bag,
                        f"{joint_topic}: no joint {', '.join(missing)} (has {', '.join(names)})",
                    ) from None
                jt.append(_stamp(m, t_ns))
                jl.append(float(m.position[il]))
                jr.append(float(m.position[ir]))
            elif con.topic == truth_topic:
                m = reader.deserialize(raw, con.msgtype)
                pose = m.pose.pose if con.msgtype == "nav_msgs/msg/Odometry" else m.pose
                q = pose.orientation
                tt.append(_stamp(m, t_ns))
                tx.append(pose.position.x)
                ty.append(pose.position.y)
                tth.append(math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y**2 + q.z**2)))
    finally:
        reader.close()
    if len(jt) < 2:
        raise GapInputError(bag, f"{joint_topic}: fewer than 2 messages")
    t = np.asarray(jt)
    bad = np.nonzero(np.diff(t) <= 0)[0]
    if bad.size:
        raise GapInputError(
            bag,
            f"{joint_topic}: message {bad[0] + 2} stamped {t[bad[0] + 1]:.6f} s does not "
            f"follow {t[bad[0]]:.6f} s (time goes backwards)",
        )
    t0, t1 = t[0], t[-1]
    truth = None
    if truth_topic is not None:
        if len(tt) < 2:
            raise GapInputError(bag, f"{truth_topic}: fewer than 2 messages")
        u = np.asarray(tt)
        bad = np.nonzero(np.diff(u) <= 0)[0]
        if bad.size:
            raise GapInputError(bag, f"{truth_topic}: message {bad[0] + 2}: time goes backwards")
        t0, t1 = max(t0, u[0]), min(t1, u[-1])
        if t1 - t0 < 2 * tick_s:
            raise GapInputError(
                bag,
                f"{joint_topic} and {truth_topic} do not overlap in time "
                "(mismatched ticks/truth lengths)",
            )
    grid = t0 + np.arange(math.floor((t1 - t0) / tick_s + 1e-9) + 1) * tick_s
    ticks = {
        "time": grid,
        "left": np.interp(grid, t, np.asarray(jl)),
        "right": np.interp(grid, t, np.asarray(jr)),
    }
    if truth_topic is not None:
        th = np.unwrap(np.asarray(tth))
        truth = {
            "time": grid,
            "x": np.interp(grid, u, np.asarray(tx)),
            "y": np.interp(grid, u, np.asarray(ty)),
            "theta": np.interp(grid, u, th),
        }
    return ticks, truth
