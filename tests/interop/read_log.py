"""Interoperability check: an independent MCAP reader (Python's `mcap` package) reads a regatta
log back, and its messages match what regatta wrote (compared with `regatta log export`).
Every message is also decoded by the ROS 2 reader that Foxglove's Python tools use
(`mcap-ros2-support`) from its channel's own schema, and the Foxglove messages say what the
run did: a scene once, a transform per step that matches the pose, one-row images, events.

It also checks that a debug and a release build of regatta write byte-identical logs.

Usage: python3 tests/interop/read_log.py PATH/TO/regatta [PATH/TO/OTHER/BUILD/regatta]
"""
import csv
import os
import struct
import subprocess
import sys
import tempfile

import math

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def main() -> int:
    regatta = sys.argv[1]
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    world = os.path.join(root, "worlds", "regatta.wbt")
    failures = 0
    checks = 0
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "run.mcap")
        subprocess.run([regatta, "run", "--steps", "500", "--log", log, world], check=True, stdout=subprocess.DEVNULL)
        subprocess.run([regatta, "log", "export", log, "--csv", os.path.join(tmp, "csv")], check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(tmp, "csv", "pose.csv")) as f:
            exported = [row for row in csv.DictReader(f)]
        poses = []
        topics = {}
        metadata = {}
        with open(log, "rb") as f:
            reader = make_reader(f)
            for record in reader.iter_metadata():
                metadata[record.name] = record.metadata
            for schema, channel, message in reader.iter_messages():
                topics[channel.topic] = topics.get(channel.topic, 0) + 1
                if channel.topic.endswith("/pose"):
                    assert schema.encoding == "ros2msg" and channel.message_encoding == "cdr"
                    t, x, z, heading = struct.unpack_from("<dddd", message.data, 4)
                    poses.append((t, x, z, heading, message.log_time))

        decoded = {}
        with open(log, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            for schema, channel, message, ros in reader.iter_decoded_messages():
                decoded.setdefault(channel.topic, []).append((schema.name, message.log_time, ros))

        def check(condition, what):
            nonlocal failures, checks
            checks += 1
            if not condition:
                failures += 1
                print("FAILED:", what)

        check("regatta" in metadata and metadata["regatta"]["seed"] == "1", "metadata record with the seed")
        check(metadata.get("regatta.end", {}).get("steps") == "500", "end record with the steps")
        check(len(poses) == 500 == len(exported), f"500 poses read ({len(poses)}) and exported ({len(exported)})")
        check(topics.get("/khepera/retina") == 500, f"a retina message per step ({topics.get('/khepera/retina')})")
        same = all(
            (log_time, x, z, h) == (int(row["t_ns"]), float(row["x"]), float(row["z"]), float(row["heading"]))
            and row["t"] == f"{log_time // 10**9}.{log_time % 10**9:09d}"
            for (t, x, z, h, log_time), row in zip(poses, exported)
        )
        check(same, "poses decoded by Python equal regatta's export bit for bit")
        check(all(log_time == round(t * 1e9) for t, _, _, _, log_time in poses), "log times are simulated time")
        check(sum(len(v) for v in decoded.values()) == sum(topics.values()), "mcap-ros2-support decodes every message")
        scene = decoded.get("/scene", [])
        check(len(scene) == 1 and scene[0][0] == "foxglove_msgs/msg/SceneUpdate", "one SceneUpdate")
        if scene:
            entities = scene[0][2].entities
            check(entities[0].frame_id == "world" and len(entities[0].cubes) >= 4, "the arena's walls in the scene")
            check([t.text for t in entities[0].texts] == ["1", "2", "3"], "numbered buoys in the scene")
        transforms = decoded.get("/tf", [])
        check(len(transforms) == 500, f"a FrameTransform per step ({len(transforms)})")
        same = all(
            tf.child_frame_id == "khepera" and tf.parent_frame_id == "world"
            and tf.translation.x == x and tf.translation.y == -z
            and abs(math.remainder(2 * math.atan2(tf.rotation.z, tf.rotation.w) - h, 2 * math.pi)) < 1e-9
            for (_, _, tf), (_, x, z, h, _) in zip(transforms, poses)
        )
        check(same, "transforms put the robot where its pose says")
        images = decoded.get("/khepera/retina/odd/image", [])
        check(
            len(images) == 500 and all(i.height == 1 and i.encoding == "mono8" and len(i.data) == i.width == i.step for _, _, i in images),
            "a one-row mono8 RawImage per retina update",
        )
        events = decoded.get("/events", [])
        check(all(e.name == "khepera" and e.message.startswith("visit ") for _, _, e in events) and len(events) > 0, f"visits as Log events ({len(events)})")
        if len(sys.argv) > 2:
            other = os.path.join(tmp, "other.mcap")
            subprocess.run([sys.argv[2], "run", "--steps", "500", "--log", other, world], check=True, stdout=subprocess.DEVNULL)
            with open(log, "rb") as a, open(other, "rb") as b:
                check(a.read() == b.read(), "the other build writes a byte-identical log")
    print(f"interop: {checks - failures} passed, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
