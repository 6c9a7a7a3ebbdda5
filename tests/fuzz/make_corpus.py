#!/usr/bin/env python3
"""Writes the fuzz seed corpora.

Seeds cut from the motion capture (BVH, ASF, AMC, and the AMC harness's skeleton) go to
FUZZ_BUILD_DIR/seeds/ and are never committed: the capture stays in ../shared/mocap.
They keep a file's header and its first few frames only (a few KB). scripts/fuzz.sh
writes them before every run. The project's own seeds (scenarios, .npy, viewer messages,
and bundles written by the harnesses themselves with the project's writers,
    MGRL_FUZZ_WRITE_SEED=FILE build-fuzz/tests/fuzz/<reader>_fuzz)
go to tests/fuzz/corpus/<reader>/.
Usage: tests/fuzz/make_corpus.py [DATA_DIR] [FUZZ_BUILD_DIR] [--capture-only]
"""
import os
import re
import struct
import subprocess
import sys

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(os.path.dirname(here))
arguments = [a for a in sys.argv[1:] if a != "--capture-only"]
capture_only = "--capture-only" in sys.argv[1:]
data = arguments[0] if len(arguments) > 0 else os.path.join(root, "..", "shared", "mocap")
build = arguments[1] if len(arguments) > 1 else os.path.join(root, "build-fuzz")
corpus = os.path.join(here, "corpus")
seeds = os.path.join(build, "seeds")


def put(reader, name, content, folder=corpus):
    os.makedirs(os.path.join(folder, reader), exist_ok=True)
    mode = "wb" if isinstance(content, bytes) else "w"
    with open(os.path.join(folder, reader, name), mode) as f:
        f.write(content)


def put_capture(reader, name, content):
    put(reader, name, content, seeds)


def cut_bvh(path, frames):
    text = open(path).read()
    head, motion = text.split("MOTION", 1)
    lines = motion.strip("\n").split("\n")
    # lines: "Frames: N", "Frame Time: t", then one line per frame
    body = lines[2:2 + frames]
    return head + "MOTION\nFrames: %d\n%s\n%s\n" % (len(body), lines[1].strip(), "\n".join(body))


# BVH: CMU and SNU skeletons, a few frames each.
for name, frames in [("cmu/bvh/13_17_boxing.bvh", 4), ("cmu/bvh/02_02_walk.bvh", 2),
                     ("snu_martial_arts/motion/16_08_1.bvh", 3), ("snu_martial_arts/t_pose_ue2.bvh", 1)]:
    put_capture("bvh", os.path.basename(name), cut_bvh(os.path.join(data, name), frames))


def cut_asf(path, bones):
    """The ASF's header, the bones named, and the hierarchy lines among them."""
    text = open(path).read()
    head, rest = text.split(":bonedata", 1)
    bonedata, hierarchy = rest.split(":hierarchy", 1)
    kept = [b for b in re.findall(r"begin\n(.*?)end", bonedata, re.S)
            if re.search(r"name (\S+)", b).group(1) in bones]
    lines = ["  begin"]
    for line in hierarchy.split("\n"):
        words = line.split()
        if words and words[0] in bones | {"root"} and words[0] not in ("begin", "end"):
            children = [w for w in words[1:] if w in bones]
            if children:
                lines.append("  " + " ".join([words[0]] + children))
    lines.append("  end")
    return ("# Cut down from CMU 02.asf (root, spine to head, left leg) for the AMC harness.\n" + head +
            ":bonedata\n" + "".join("  begin\n" + b + "end\n" for b in kept) + ":hierarchy\n" +
            "\n".join(lines) + "\n")


# ASF: the AMC harness's skeleton (root, spine to head, left leg of CMU 02.asf).
skeleton = cut_asf(os.path.join(data, "cmu/asfamc/02.asf"),
                   {"lhipjoint", "lfemur", "ltibia", "lfoot", "lowerback", "upperback", "thorax",
                    "lowerneck", "upperneck", "head"})
os.makedirs(seeds, exist_ok=True)
with open(os.path.join(seeds, "amc_skeleton.asf"), "w") as f:
    f.write(skeleton)
put_capture("asf", "skeleton.asf", skeleton)


def cut_amc(path, frames, bones):
    out, count = [], 0
    for line in open(path).read().split("\n"):
        if re.fullmatch(r"\d+", line.strip()):
            count += 1
            if count > frames:
                break
            out.append(line)
        elif line.startswith((":", "#")) or line.split(" ")[0] in bones:
            out.append(line)
    return "\n".join(out) + "\n"


bones = {"root"} | set(re.findall(r"name (\S+)", skeleton))
amc = cut_amc(os.path.join(data, "cmu/asfamc/02_02.amc"), 4, bones)
put_capture("amc", "02_02_cut.amc", amc)
put_capture("amc", "07_05_cut.amc", cut_amc(os.path.join(data, "cmu/asfamc/07_05.amc"), 2, bones))
# The ASF harness also takes an AMC after the ASF.
put_capture("asf", "skeleton_with_amc.asf", skeleton + "\n@@file x.amc\n" + amc)
if capture_only:
    sys.exit(0)

# Scenarios: the project's own.
for name in ("boxing.yaml", "sparring.yaml"):
    put("scenario", name, open(os.path.join(root, "scenarios", name)).read())


# .npy: each element type the bundles use, 1.0 and 2.0 headers.
def npy(descr, shape, payload, version=1):
    shape_text = "(%s)" % (", ".join(str(d) for d in shape) + ("," if len(shape) == 1 else ""))
    header = "{'descr': '%s', 'fortran_order': False, 'shape': %s, }" % (descr, shape_text)
    prefix = 10 if version == 1 else 12
    pad = 64 - (prefix + len(header) + 1) % 64
    header = header + " " * (pad % 64) + "\n"
    size = struct.pack("<H", len(header)) if version == 1 else struct.pack("<I", len(header))
    return b"\x93NUMPY" + bytes([version, 0]) + size + header.encode() + payload


put("npy", "f4_2x3.npy", npy("<f4", (2, 3), struct.pack("<6f", *range(6))))
put("npy", "f8_3.npy", npy("<f8", (3,), struct.pack("<3d", 0.5, -1, 2)))
put("npy", "i4_2x2.npy", npy("<i4", (2, 2), struct.pack("<4i", 1, -2, 3, 4)))
put("npy", "u4_0d.npy", npy("<u4", (), struct.pack("<I", 7)))
put("npy", "u1_4_v2.npy", npy("|u1", (4,), bytes([1, 2, 3, 4]), version=2))

# Viewer protocol: the page's messages (docs/viewer-protocol.md).
for i, message in enumerate([
        '{"type": "mode", "mode": "crowd", "avatars": 30}',
        '{"type": "move_target", "avatar": 0, "position": [0.5, 1.2, 0.8]}',
        '{"type": "controller", "controller": "online_search", "horizon": 3}',
        '{"type": "weights", "weights": {"approach": 1, "hit": 2}}',
        '{"type": "pause", "paused": true}', '{"type": "step"}', '{"type": "speed", "speed": 0.5}',
        '{"type": "values", "behavior": "hit"}',
        '{"type": "learn", "command": "start", "behavior": "approach", "seed": 1, "budget": 20000}',
        '{"type": "learn", "command": "step", "steps": 10}',
        '{"type": "retrain", "behavior": "hit", "set": {"reward.contact_radius": 0.2}}']):
    put("protocol", "message_%02d.json" % i, message)

# Bundles, by the harnesses (built in FUZZ_BUILD_DIR).
for reader in ("graph_cache", "policy_bundle", "checkpoint"):
    program = os.path.join(build, "tests", "fuzz", reader + "_fuzz")
    if not os.path.exists(program):
        print("skipping the %s seed: %s is not built" % (reader, program))
        continue
    os.makedirs(os.path.join(corpus, reader), exist_ok=True)
    seed = os.path.join(corpus, reader, "saved")
    subprocess.run([program], env=dict(os.environ, MGRL_FUZZ_WRITE_SEED=seed), check=True)

for folder in (seeds, corpus):
    for reader in sorted(r for r in os.listdir(folder) if os.path.isdir(os.path.join(folder, r))):
        files = os.listdir(os.path.join(folder, reader))
        sizes = [os.path.getsize(os.path.join(folder, reader, f)) for f in files]
        print("%-14s %2d files, largest %5d bytes (%s)" % (reader, len(files), max(sizes), folder))
