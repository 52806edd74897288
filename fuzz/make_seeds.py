#!/usr/bin/env python3
"""Writes the hand-made seed inputs of the fuzz corpora (fuzz/corpus/<target>/seed-*).

Link messages follow hil-stubs/src/protocol/mod.rs (protocol version 12: 24-byte header,
payload, CRC-32/ISO-HDLC trailer = zlib.crc32, the whole COBS-framed between two zero bytes;
frames carry RGB565 images, 2 bytes a pixel). Run from anywhere: python3 fuzz/make_seeds.py
"""
import os
import re
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
VERSION = 13
TABLE = os.path.join(HERE, "..", "core", "src", "tuning", "table.rs")


def tuning_table():
    """(name, kind) of every field of the core's tuning table, in order (kind 1 real, 2 int, 3 name)."""
    text = open(TABLE, encoding="utf-8").read()
    kinds = {"real": 1, "int": 2}
    rows = re.findall(r'(real|int)!\(\s*"([^"]+)"|name: "([^"]+)",\s*unit: "[^"]*",\s*meaning: "[^"]*",\s*kind: Kind::Name', text)
    return [(m[2], 3) if m[2] else (m[1], kinds[m[0]]) for m in rows]


def table_id(table):
    """The core's tuning::TABLE_ID: FNV-1a over every name's bytes and kind, in order."""
    h = 0x811C9DC5
    for name, kind in table:
        for b in name.encode():
            h = ((h ^ b) * 0x01000193) % 2**32
        h = ((h ^ kind) * 0x01000193) % 2**32
    return h


# Tuning::DEFAULT in the table's order: method ("ff+target", index 2), hue tolerance, max dt,
# generations per frame, the GA
# (population, three probabilities, immigrants, tournament, the level CDF, the settled CDF and
# fitness, the mutation scales), the acquisition, the status, the target motion model.
DEFAULT_TUNING = (
    [2, 5, 0.5, 2, 40, 0.2, 0.9, 0.35, 1, 3, 0.25, 0.6, 0.15, 0.5, 0.95]
    + [0.02, 0.02, 0.02, 0.04, 0.04, 0.04, 0.004, 0.004, 0.004, 0.008, 0.008, 0.008]
    + [0.001, 0.001, 0.001, 0.004, 0.004, 0.004]
    + [8, 1200, 8, 6, 6, 0.003, 0.010, 0.025, 0.03, 0.10, 0.25]
    + [0.75, 3, 0.9, 0.4, 1, 150]
    + [1.0, 2.0, 0.5, 1.0, 0.5, 0.5]
)


def tuning():
    """The tuning part of CONFIG: table id, count (+2 reserved), each field's 4 bytes."""
    table = tuning_table()
    assert len(table) == len(DEFAULT_TUNING), (len(table), len(DEFAULT_TUNING))
    p = struct.pack("<IHH", table_id(table), len(table), 0)
    for (name, kind), v in zip(table, DEFAULT_TUNING):
        p += f32s(v) if kind == 1 else struct.pack("<I", v)
    return p


def cobs(raw):
    """COBS-encodes raw (no zero byte in the result)."""
    out, run = bytearray(), bytearray()
    for b in raw:
        if b == 0:
            out += bytes([len(run) + 1]) + run
            run = bytearray()
        else:
            run.append(b)
            if len(run) == 254:
                out += b"\xff" + run
                run = bytearray()
    return bytes(out + bytes([len(run) + 1]) + run)


def msg(kind, payload=b"", seq=0, time_us=0, flags=0):
    header = b"EVRC" + bytes([VERSION, kind]) + struct.pack("<HIIQ", flags, seq, len(payload), time_us)
    body = header + payload
    return b"\0" + cobs(body + struct.pack("<I", zlib.crc32(body))) + b"\0"


def f32s(*v):
    return struct.pack("<%df" % len(v), *v)


def setup(width, height):
    """A CONFIG payload: the protocol tests' sample setup at the given image size."""
    p = f32s(width * 1.25, width * 1.25, width / 2, height / 2)
    p += struct.pack("<HH", width, height)
    p += f32s(0.1)  # baseline
    p += f32s(0.1, 0.15, 0.2)  # block
    p += f32s(0, 120, 240, 0, 120, 240)  # face hues
    p += f32s(0, 0.06, 0.1) + f32s(1, 0, 0, 0)  # flange to camera
    p += f32s(-0.2, -0.2, 0.4) + f32s(0.2, 0.2, 1.0)  # search box
    p += struct.pack("<Q", 1)  # seed
    p += tuning()
    p += f32s(0, 0, 0.7, 0, 0, 0) + f32s(*[0.02] * 6)  # initial pose and spread
    return p


def frame(width, height, t_us, shade):
    """A FRAME payload with two RGB565 images (little-endian u16 per pixel)."""
    p = struct.pack("<HHQ", width, height, t_us) + f32s(*[0.1] * 7) + f32s(*[0.01] * 7)
    n = width * height
    left = b"".join(struct.pack("<H", (shade * 257 + 977 * i) % 65536) for i in range(n))
    return p + left + left[::-1]


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


def main():
    w, h = 16, 12
    config = msg(1, setup(w, h))
    frames = b"".join(msg(2, frame(w, h, 33_333 * k, 10 * k), seq=k, time_us=33_333 * k) for k in range(1, 3))
    end = msg(4)
    write("link_decode", "config", config)
    write("link_decode", "frame", msg(2, frame(4, 3, 7, 0), seq=5, time_us=9))
    write("link_decode", "stream", config + frames + end)
    write("firmware_serve", "conversation", config + frames + end)
    write("firmware_serve", "wrong-size-frame", config + msg(2, frame(4, 3, 1, 0), seq=1) + end)
    superseded = msg(2, frame(w, h, 33_333, 10), seq=1, time_us=33_333, flags=1)
    write("firmware_serve", "overload", config + superseded + frames[len(frames) // 2 :] + end)
    # A superseded frame cut in its images: the board's bulk skip meets the next delimiter.
    write("firmware_serve", "overload-cut", config + superseded[: len(superseded) // 2] + frames + end)
    damaged = bytearray(frames)
    damaged[60] ^= 0x10
    write("firmware_serve", "damaged", config + bytes(damaged[: len(damaged) - 40]) + frames + end)
    replies = msg(5, struct.pack("<I", 0))
    replies += msg(3, f32s(0.01, -0.02, 0.7, 0.05, 0.1, -0.03, 0.9, 0.88, 0.92) + struct.pack("<IB", 1, 1) + f32s(0.011, -0.02, 0.7, 0.05, 0.1, -0.03), seq=1, time_us=33_333)
    replies += msg(6, seq=2, time_us=66_666)
    replies += msg(7, struct.pack("<13I", 2, 1, 1, 13_892, 90_000, 1, 0, 0, 2, 0, 1, 0, 0))
    write("host_replies", "conversation", replies)
    write("host_replies", "error", msg(8, struct.pack("<I", 2)))
    # tracker_step: camera 16x12, no reset, one step on 16x12 RGB565 images with zero joints, dt 0.033
    step = bytes([16, 12, 0]) + struct.pack("<HHHH", 16, 12, 16, 12) + bytes([7, 1])
    step += bytes((i * 13) % 256 for i in range(2 * 16 * 12)) + f32s(*[0.0] * 14) + f32s(0.033) + bytes([1])
    write("tracker_step", "one-step", step)
    write("tracker_step", "nan-joints", step[: -(14 * 4 + 5)] + f32s(float("nan"), *[0.0] * 13) + f32s(0.033) + b"\1")
    with open(os.path.join(HERE, "..", "scenarios", "smoke.toml"), "rb") as f:
        write("scenario_toml", "smoke", f.read())
    write("scenario_toml", "minimal", b'seed = 1\nduration_s = 1.0\nmethod = "ga"\n')
    sequence_seeds()


SEQUENCE_TOML = b"""format = "evorec-seq/1"
name = "seed"

[robot]
urdf = "robot.urdf"
base_link = "base_link"
flange_link = "flange_link"

[cameras]
left = "calib/left.yaml"
right = "calib/right.yaml"
right_to_left = [1.0, 0.0, 0.0, 0.1,  0.0, 1.0, 0.0, 0.0,  0.0, 0.0, 1.0, 0.0,  0.0, 0.0, 0.0, 1.0]
flange_to_right = [0.0, 1.0, 0.0, -0.04,  -1.0, 0.0, 0.0, -0.05,  0.0, 0.0, 1.0, 0.1,  0.0, 0.0, 0.0, 1.0]

[target]
size_m = [0.1, 0.15, 0.2]
face_hues_deg = [0.0, 120.0, 240.0, 0.0, 120.0, 240.0]
initial_pose = { t_m = [-0.05, 0.0, 0.7], q_xyzw = [0.0, 0.0, 0.0, 1.0] }

[search]
min_m = [-0.3, -0.3, 0.4]
max_m = [0.3, 0.3, 1.0]
"""

CAMERA_INFO = b"""image_width: 640
image_height: 480
camera_name: left
camera_matrix:
  rows: 3
  cols: 3
  data: [800.0, 0.0, 319.5, 0.0, 800.0, 239.5, 0.0, 0.0, 1.0]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.2, 0.05, 0.001, -0.001, 0.0]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
projection_matrix:
  rows: 3
  cols: 4
  data: [800.0, 0.0, 319.5, 0.0, 0.0, 800.0, 239.5, 0.0, 0.0, 0.0, 1.0, 0.0]
"""

URDF_2DOF = b"""<robot name="seed">
  <link name="base_link"/>
  <link name="l1"/>
  <link name="flange_link"/>
  <joint name="j1" type="revolute">
    <parent link="base_link"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="j2" type="prismatic">
    <parent link="l1"/><child link="flange_link"/>
    <origin xyz="0.1 0 0" rpy="0 1.5707963 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.5" effort="1" velocity="1"/>
  </joint>
</robot>
"""


def sequence_seeds():
    """sequence_files: the first byte picks the reader (0 sequence.toml, 1 camera_info, 2 URDF,
    3 frames.csv, 4 joints.csv with joints j1 j2, 5 TUM)."""
    write("sequence_files", "manifest", b"\0" + SEQUENCE_TOML)
    write("sequence_files", "camera-info", b"\1" + CAMERA_INFO)
    write("sequence_files", "urdf", b"\2" + URDF_2DOF)
    with open(os.path.join(HERE, "..", "robots", "pa10.urdf"), "rb") as f:
        write("sequence_files", "urdf-pa10", b"\2" + f.read())
    frames = b"index,t_s,left,right\n" + b"".join(
        b"%d,%.9f,left/%06d.png,right/%06d.png\n" % (k, k / 30, k, k) for k in range(3)
    )
    write("sequence_files", "frames", b"\3" + frames)
    joints = b"t_s,pos_j1,pos_j2,vel_j1,vel_j2\n" + b"".join(
        b"%.3f,%.4f,%.4f,0.1,-0.2\n" % (k * 0.002, 0.1 * k, 0.2 - 0.001 * k) for k in range(4)
    )
    write("sequence_files", "joints", b"\4" + joints)
    tum = b"# t tx ty tz qx qy qz qw\n0.0 -0.05 0.0 0.7 0.0 0.0 0.0 1.0\n0.033 -0.05 0.0 0.7 0.0 0.0 0.6 0.8\n"
    write("sequence_files", "tum", b"\5" + tum)


if __name__ == "__main__":
    main()
