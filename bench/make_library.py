"""Scale a folder of BVH clips up to a chosen number of hours of capture, for benchmarks.

    /usr/bin/python3 bench/make_library.py --hours H --out DIR [--source DIR] [--seed S]
                                           [--force] [--show-mirror]

The library written to DIR holds the source clips first, unchanged, then copies of them,
clip by clip in name order and round after round, until the total duration reaches H
hours. Each copy is one of:

  * time-warped: resampled by a speed factor drawn log-uniformly from 0.80..1.25 (rounded
    to 0.01; above 1 the copy is shorter). Every channel is interpolated linearly between
    neighbouring frames; Euler angles are unwrapped over time first, so that a channel
    going 179 -> -179 turns by 2 degrees, not by 358. Where a joint's angles pass near
    gimbal lock between two frames (two angles swing by up to 180 degrees while the joint
    barely turns; under 0.1 % of the joint-frames of the Bandai Namco clips) its in-between
    frames follow the shortest arc between the two rotations instead;
  * mirrored left-right: the channel data of each joint named ..._L is swapped with its
    ..._R twin and the whole motion is reflected across a vertical world plane;
  * both.

The name of a copy says what it is: dataset-1_walk_normal_001__w1.13_m.bvh is
dataset-1_walk_normal_001.bvh played at 1.13 times its speed and mirrored; __m alone is a
mirror at the original speed, __w0.91 alone a warp without mirroring. No copy repeats
another's variant of the same clip, and none is an unmodified clip. The file that makes the
total reach H hours is cut to the frames still needed (never below one second, so the
total may pass H by less than a second); its name then ends in _cutN, N its frame count.

Every file keeps its source's HIERARCHY block byte for byte; MOTION has the new frame
count, the source's Frame Time line and the values with six significant digits. Files are
written under a temporary name and renamed when complete. The draws come from --seed
alone, so the same source, hours and seed give the same library.

Mirroring. The reflection is found from the skeleton, not assumed. A skeleton whose rest
pose is symmetric (T-pose, world-aligned joint frames) mirrors with one sign pattern: for
a reflection x -> -x, X positions negate, X rotations stay, Y and Z rotations negate. Game
exports instead give joints their own frames (the left arm's bones run along +X, the
right arm's along -X; the hips separate the legs along Y, the chest the shoulders along
Z), so each joint j gets its own reflection S_j, a diagonal sign matrix with determinant
-1, chosen so that S_j maps the offsets of j's children (position channel values where the
joint has them) onto the offsets of its twin's children. When the offsets leave a choice
(a bone with a single child along its axis leaves the twist open) the motion decides: the
candidate whose mirrored mean local rotation best matches the twin's mean rotation over
all source frames. The world gets the reflection across the vertical plane perpendicular
to the horizontal axis that the _L -> _R joint vectors follow most (in world space, over
all source frames). With S_p the parent's reflection (the world's for a root), the twin j'
of joint j gets

    position channels  t'  = S_p t
    rotation           R'  = S_p R S_j,

which keeps every Euler angle a signed copy of one source angle, plus 180 degrees when
S_p and S_j differ; the channel order each joint declares is respected. --show-mirror
prints the reflections found.

Errors (a malformed BVH, a missing source folder, a non-positive --hours, a non-empty DIR
without --force) are one line naming the file and what was expected and found. A progress
line goes to stderr at every 10 % and a one-line summary to stdout.
"""
import argparse
import math
import os
import pathlib
import random
import re
import sys
from dataclasses import dataclass, field

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
AXES = "XYZ"
SPEED_MIN, SPEED_MAX = 0.80, 1.25
DIGITS = 6  # significant digits of the values written


class LibraryError(Exception):
    """A problem the user must fix; main() prints it as one line and exits with 1."""


# ---------------------------------------------------------------------------------------
# Reading and writing BVH


@dataclass
class Joint:
    name: str
    parent: int  # index of the parent joint, -1 for a root
    offset: np.ndarray
    channels: list  # channel names as declared, e.g. ["Xposition", ..., "Zrotation"]
    first_column: int  # column of the joint's first channel in a frame line
    children: list = field(default_factory=list)
    end_sites: list = field(default_factory=list)  # End Site offsets

    def column(self, channel):
        return self.first_column + self.channels.index(channel)

    def rotation_axes(self):
        return [c[0] for c in self.channels if c.endswith("rotation")]


@dataclass
class Clip:
    path: pathlib.Path
    hierarchy_text: str  # everything before MOTION, verbatim
    frame_time_line: str  # the "Frame Time:" line, verbatim
    frame_time: float
    joints: list
    data: np.ndarray  # frames x channels

    @property
    def frames(self):
        return self.data.shape[0]

    @property
    def seconds(self):
        return self.frames * self.frame_time

    def signature(self):
        """Joint names, parents and channels: clips with equal signatures mirror alike."""
        return tuple((j.name, j.parent, tuple(j.channels)) for j in self.joints)


CHANNEL_NAMES = {a + kind for a in AXES for kind in ("position", "rotation")}


class HierarchyReader:
    """Recursive-descent reader of a HIERARCHY block; errors name file and line."""

    def __init__(self, path, text, end="the MOTION line"):
        self.path = path
        self.end = end  # what follows the hierarchy text, for "found ..." messages
        self.tokens = [(tok, number) for number, line in enumerate(text.splitlines(), 1)
                       for tok in line.split()]
        self.pos = 0
        self.last_line = text.count("\n") + 1
        self.joints = []
        self.columns = 0

    def fail(self, expected, found=None, line=None):
        if found is None:
            found = repr(self.tokens[self.pos][0]) if self.pos < len(self.tokens) else self.end
        if line is None:
            line = self.tokens[self.pos][1] if self.pos < len(self.tokens) else self.last_line
        raise LibraryError(f"{self.path}:{line}: expected {expected}, found {found}")

    def next(self, expected):
        if self.pos >= len(self.tokens):
            self.fail(expected)
        token = self.tokens[self.pos][0]
        self.pos += 1
        return token

    def expect(self, word):
        if self.pos >= len(self.tokens) or self.tokens[self.pos][0] != word:
            self.fail(repr(word))
        self.pos += 1

    def number(self, what):
        if self.pos < len(self.tokens):
            try:
                value = float(self.tokens[self.pos][0])
            except ValueError:
                value = None
            if value is not None and math.isfinite(value):
                self.pos += 1
                return value
        self.fail(what)

    def offset(self):
        self.expect("OFFSET")
        return np.array([self.number("an OFFSET coordinate") for _ in range(3)])

    def parse(self):
        self.expect("HIERARCHY")
        while self.pos < len(self.tokens):
            self.expect("ROOT")
            self.joint(-1)
        if not self.joints:
            self.fail("'ROOT'")
        return self.joints

    def joint(self, parent):
        name = self.next("a joint name")
        self.expect("{")
        offset = self.offset()
        channels = []
        if self.pos < len(self.tokens) and self.tokens[self.pos][0] == "CHANNELS":
            self.pos += 1
            count = self.number("a channel count")
            if count != int(count) or not 0 <= count <= 6:
                self.fail("a channel count of 0 to 6", repr(self.tokens[self.pos - 1][0]), self.tokens[self.pos - 1][1])
            for _ in range(int(count)):
                token = self.next("a channel name (Xposition ... Zrotation)")
                if token not in CHANNEL_NAMES or token in channels:
                    self.pos -= 1
                    self.fail("a channel name (Xposition ... Zrotation), each once")
                channels.append(token)
        index = len(self.joints)
        self.joints.append(Joint(name, parent, offset, channels, self.columns))
        self.columns += len(channels)
        if parent >= 0:
            self.joints[parent].children.append(index)
        while True:
            if self.pos >= len(self.tokens):
                self.fail("'JOINT', 'End Site' or '}'")
            token = self.tokens[self.pos][0]
            if token == "}":
                self.pos += 1
                return
            if token == "JOINT":
                self.pos += 1
                self.joint(index)
            elif token == "End":
                self.pos += 1
                self.expect("Site")
                self.expect("{")
                self.joints[index].end_sites.append(self.offset())
                self.expect("}")
            else:
                self.fail("'JOINT', 'End Site' or '}'")


MOTION_LINE = re.compile(r"^[ \t]*MOTION[ \t]*\r?$", re.MULTILINE)


def read_bvh(path):
    """Parse a BVH file into a Clip; raise LibraryError naming the file and line if malformed."""
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="ascii", errors="replace")
    except OSError as err:
        raise LibraryError(f"{path}: cannot read: {err.strerror}")
    match = MOTION_LINE.search(text)
    if not match:
        HierarchyReader(path, text, "end of file").parse()  # names the first fault of a cut or broken hierarchy
        raise LibraryError(f"{path}: expected a line 'MOTION' after the hierarchy, found none")
    hierarchy_text = text[:match.start()]
    joints = HierarchyReader(path, hierarchy_text).parse()
    columns = sum(len(j.channels) for j in joints)
    if columns == 0:
        raise LibraryError(f"{path}: expected at least one channel in the hierarchy, found none")

    first_line = hierarchy_text.count("\n") + 2  # line number of the line after MOTION
    lines = text[match.end():].split("\n")[1:]
    numbered = [(n, line) for n, line in enumerate(lines, first_line) if line.strip()]

    def header(index, label):
        if index >= len(numbered):
            raise LibraryError(f"{path}:{first_line + len(lines) - 1}: expected '{label}', found end of file")
        number, line = numbered[index]
        if not line.strip().startswith(label):
            raise LibraryError(f"{path}:{number}: expected '{label}', found {line.strip()[:40]!r}")
        value = line.strip()[len(label):].strip()
        try:
            parsed = float(value)
        except ValueError:
            parsed = math.nan
        if not math.isfinite(parsed) or parsed < 0:
            raise LibraryError(f"{path}:{number}: expected a number after '{label}', found {value[:40]!r}")
        return number, line.rstrip("\r"), parsed

    number, _, declared = header(0, "Frames:")
    if declared != int(declared):
        raise LibraryError(f"{path}:{number}: expected a whole frame count, found {declared}")
    number, frame_time_line, frame_time = header(1, "Frame Time:")
    if frame_time <= 0:
        raise LibraryError(f"{path}:{number}: expected a positive frame time, found {frame_time}")

    rows = numbered[2:]
    if len(rows) != int(declared):
        raise LibraryError(f"{path}: expected {int(declared)} frame lines (Frames:), found {len(rows)}")
    if not rows:
        raise LibraryError(f"{path}: expected at least one frame, found 'Frames: 0'")
    values = []
    for number, line in rows:
        fields = line.split()
        if len(fields) != columns:
            raise LibraryError(f"{path}:{number}: expected {columns} channel values, found {len(fields)}")
        values.append(fields)
    try:
        data = np.array(values, dtype=float)
    except ValueError:
        for number, line in rows:
            for token in line.split():
                try:
                    float(token)
                except ValueError:
                    raise LibraryError(f"{path}:{number}: expected a number, found {token[:40]!r}")
        raise
    if not np.isfinite(data).all():
        row = int(np.nonzero(~np.isfinite(data).all(axis=1))[0][0])
        raise LibraryError(f"{path}:{rows[row][0]}: expected finite channel values, found nan or inf")
    return Clip(path, hierarchy_text, frame_time_line, frame_time, joints, data)


def format_motion(clip, data):
    """The text of a BVH file: the clip's hierarchy verbatim, then data as MOTION."""
    row = " ".join([f"%.{DIGITS}g"] * data.shape[1])
    # Adding 0.0 turns -0.0 (a negated zero) into 0.0, so "-0" is never written.
    body = "\n".join(row % tuple(values) for values in (data + 0.0).tolist())
    return f"{clip.hierarchy_text}MOTION\nFrames: {data.shape[0]}\n{clip.frame_time_line}\n{body}\n"


def write_atomically(path, content):
    """Write content to a temporary name beside path, then rename it into place."""
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        if isinstance(content, bytes):
            temporary.write_bytes(content)
        else:
            temporary.write_text(content, encoding="ascii")
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


# ---------------------------------------------------------------------------------------
# Rotations


def axis_rotation(axis, degrees):
    """Rotation matrices about X, Y or Z for an array of angles: shape (..., 3, 3)."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    one, zero = np.ones_like(c), np.zeros_like(c)
    rows = {"X": [[one, zero, zero], [zero, c, -s], [zero, s, c]],
            "Y": [[c, zero, s], [zero, one, zero], [-s, zero, c]],
            "Z": [[c, -s, zero], [s, c, zero], [zero, zero, one]]}[axis]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def local_transforms(joints, data):
    """Per joint: local rotations (frames x 3 x 3) and translations (frames x 3).

    Rotations compose in the order the channels are declared; position channels replace
    the OFFSET's coordinates (as mgrl reads them).
    """
    frames = data.shape[0]
    rotations, translations = [], []
    for joint in joints:
        rotation = np.broadcast_to(np.eye(3), (frames, 3, 3))
        translation = np.tile(joint.offset, (frames, 1))
        for i, channel in enumerate(joint.channels):
            values = data[:, joint.first_column + i]
            if channel.endswith("rotation"):
                rotation = rotation @ axis_rotation(channel[0], values)
            else:
                translation[:, AXES.index(channel[0])] = values
        rotations.append(np.array(rotation))
        translations.append(translation)
    return rotations, translations


def forward_kinematics(joints, data):
    """World positions of every joint, frames x joints x 3."""
    rotations, translations = local_transforms(joints, data)
    frames = data.shape[0]
    world_rotation, positions = [], np.zeros((frames, len(joints), 3))
    for index, joint in enumerate(joints):
        if joint.parent < 0:
            world_rotation.append(rotations[index])
            positions[:, index] = translations[index]
        else:
            parent_rotation = world_rotation[joint.parent]
            positions[:, index] = positions[:, joint.parent] + np.einsum(
                "fij,fj->fi", parent_rotation, translations[index])
            world_rotation.append(parent_rotation @ rotations[index])
    return positions


def euler_matrices(axes, degrees):
    """Rotation matrices of Euler angles (frames x len(axes)) composed in the order axes."""
    result = np.broadcast_to(np.eye(3), degrees.shape[:-1] + (3, 3))
    for i, axis in enumerate(axes):
        result = result @ axis_rotation(axis, degrees[..., i])
    return np.array(result)


def euler_angles(axes, matrix, near):
    """Angles (degrees) about three distinct axes, in that order, that compose to matrix;
    of the two solutions, the one nearest `near`, each angle moved by whole turns next to it."""
    i, j, k = (AXES.index(a) for a in axes)
    parity = 1.0 if (i, j, k) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0
    middle = np.degrees(np.arcsin(np.clip(parity * matrix[i, k], -1.0, 1.0)))
    first = np.degrees(np.arctan2(-parity * matrix[j, k], matrix[k, k]))
    last = np.degrees(np.arctan2(-parity * matrix[i, j], matrix[i, i]))
    best = None
    for candidate in (np.array([first, middle, last]), np.array([first + 180.0, 180.0 - middle, last + 180.0])):
        candidate = near + wrap_degrees(candidate - near)
        distance = np.abs(candidate - near).sum()
        if best is None or distance < best[0]:
            best = (distance, candidate)
    return best[1]


def rotation_log(matrix):
    """Axis times angle (radians) of rotation matrices (..., 3, 3) -> (..., 3)."""
    angle = np.arccos(np.clip((np.trace(matrix, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0))
    skew = np.stack([matrix[..., 2, 1] - matrix[..., 1, 2], matrix[..., 0, 2] - matrix[..., 2, 0],
                     matrix[..., 1, 0] - matrix[..., 0, 1]], axis=-1)
    sine = np.sin(angle)
    factor = np.where(sine > 1e-9, angle / (2.0 * np.maximum(sine, 1e-9)), 0.5)
    result = factor[..., None] * skew
    # Near a half turn the skew part vanishes; the axis is then the longest column of
    # (R + I) / 2 (the sign of a half turn's axis does not matter).
    for index in zip(*np.nonzero((angle > 3.0) & (sine <= 1e-6))):
        half = (matrix[index] + np.eye(3)) / 2.0
        column = half[:, int(np.argmax(np.diag(half)))]
        result[index] = angle[index] * column / np.linalg.norm(column)
    return result


def rotation_exp(vector):
    """Rotation matrices of axis-times-angle vectors (..., 3) -> (..., 3, 3) (Rodrigues)."""
    angle = np.linalg.norm(vector, axis=-1)
    axis = vector / np.maximum(angle, 1e-300)[..., None]
    x, y, z = axis[..., 0], axis[..., 1], axis[..., 2]
    zero = np.zeros_like(x)
    cross = np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1),
                      np.stack([-y, x, zero], -1)], -2)
    sine, versine = np.sin(angle)[..., None, None], (1.0 - np.cos(angle))[..., None, None]
    return np.eye(3) + sine * cross + versine * (cross @ cross)


def slerp(a, b, weight):
    """Rotations a fraction weight of the way along the shortest arcs from a to b."""
    relative = np.swapaxes(a, -1, -2) @ b
    return a @ rotation_exp(np.asarray(weight)[..., None] * rotation_log(relative))


def geodesic_degrees(a, b):
    """Angles between stacks of rotation matrices."""
    cosine = (np.einsum("...ij,...ij->...", a, b) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


# ---------------------------------------------------------------------------------------
# Time warping


def rotation_columns(joints):
    return np.array([j.first_column + i for j in joints for i, c in enumerate(j.channels)
                     if c.endswith("rotation")], dtype=int)


def wrap_degrees(values):
    """Angles brought into [-180, 180)."""
    return (values + 180.0) % 360.0 - 180.0


def warped_frame_count(frames, speed):
    return frames if frames < 2 else max(2, int(round((frames - 1) / speed)) + 1)


# Between two frames, linear interpolation of Euler angles follows nearly the shortest arc
# (typically the midpoints differ by hundredths of a degree) unless the angles pass near gimbal lock,
# where two of them swing by up to 180 degrees while the joint barely turns. Intervals whose
# Euler midpoint is further than this from the shortest-arc midpoint are interpolated along
# the shortest arc instead.
GIMBAL_TOLERANCE_DEG = 1.0


def time_warp(data, joints, speed):
    """Resample frames x channels data to play `speed` times as fast.

    The first and last frames are kept; in between every channel is interpolated linearly,
    the rotation channels after unwrapping them over time (and wrapped back afterwards).
    Where a joint's Euler angles pass near gimbal lock between two frames (see
    GIMBAL_TOLERANCE_DEG), its in-between frames follow the shortest arc instead.
    """
    frames = data.shape[0]
    count = warped_frame_count(frames, speed)
    if count == frames:
        return data.copy()
    rotations = rotation_columns(joints)
    smooth = data.copy()
    smooth[:, rotations] = np.unwrap(data[:, rotations], period=360.0, axis=0)
    at = np.linspace(0.0, frames - 1, count)
    low = np.minimum(np.floor(at).astype(int), frames - 2)
    weight = at - low
    out = smooth[low] * (1.0 - weight[:, None]) + smooth[low + 1] * weight[:, None]
    for joint in joints:
        axes = joint.rotation_axes()
        if len(axes) != 3:
            continue
        columns = [joint.column(a + "rotation") for a in axes]
        pose = euler_matrices(axes, smooth[:, columns])
        euler_middle = euler_matrices(axes, (smooth[:-1, columns] + smooth[1:, columns]) / 2.0)
        arc_middle = slerp(pose[:-1], pose[1:], 0.5)
        for interval in np.nonzero(geodesic_degrees(euler_middle, arc_middle) > GIMBAL_TOLERANCE_DEG)[0]:
            for k in np.nonzero((low == interval) & (weight > 0.0))[0]:
                matrix = slerp(pose[interval], pose[interval + 1], weight[k])
                out[k, columns] = euler_angles(axes, matrix, out[k, columns])
    out[:, rotations] = wrap_degrees(out[:, rotations])
    return out


# ---------------------------------------------------------------------------------------
# Mirroring


def twin_name(name):
    if name.endswith("_L"):
        return name[:-2] + "_R"
    if name.endswith("_R"):
        return name[:-2] + "_L"
    return name


SIGN_CANDIDATES = [np.array(s, dtype=float) for s in
                   ((-1, 1, 1), (1, -1, 1), (1, 1, -1), (-1, -1, -1))]


def describe_signs(signs):
    return "diag(" + ",".join("+" if s > 0 else "-" for s in signs) + ")"


@dataclass
class MirrorPlan:
    """How to mirror frames of one skeleton: out = data[:, source] * scale + shift."""
    source: np.ndarray
    scale: np.ndarray
    shift: np.ndarray
    world_signs: np.ndarray
    joint_signs: list
    notes: list

    def apply(self, data):
        out = data[:, self.source] * self.scale + self.shift
        shifted = self.shift != 0
        out[:, shifted] = wrap_degrees(out[:, shifted])
        return out


def effective_offsets(clips):
    """Per joint: its OFFSET with position-channel coordinates replaced by their mean over
    all frames, and per coordinate whether those channel values move (root motion)."""
    joints = clips[0].joints
    data = np.concatenate([c.data for c in clips])
    offsets, moving = [], []
    for index, joint in enumerate(joints):
        offset = np.mean([c.joints[index].offset for c in clips], axis=0)
        moves = np.zeros(3, dtype=bool)
        for i, channel in enumerate(joint.channels):
            if channel.endswith("position"):
                values = data[:, joint.first_column + i]
                k = AXES.index(channel[0])
                offset[k] = values.mean()
                moves[k] = values.std() > 1e-3 * (1.0 + abs(values.mean()))
        if not moves.any():
            spread = np.ptp([c.joints[index].offset for c in clips], axis=0)
            moves = spread > 1e-3 * (1.0 + np.abs(offset))
        offsets.append(offset)
        moving.append(moves)
    return offsets, moving


def offset_constraints(joint_index, joints, twins, offsets, moving):
    """Pairs (offset of a child of joint, offset of the twin's corresponding child)."""
    joint, twin = joints[joint_index], joints[twins[joint_index]]
    pairs = []
    by_name = {joints[c].name: c for c in twin.children}
    for child in joint.children:
        partner = by_name.get(twin_name(joints[child].name))
        if partner is None:
            raise LibraryError(f"{joint.name}'s child {joints[child].name} has no twin "
                               f"{twin_name(joints[child].name)} under {twin.name}")
        if not (moving[child].any() or moving[partner].any()):
            pairs.append((offsets[child], offsets[partner]))
    if len(joint.end_sites) != len(twin.end_sites):
        raise LibraryError(f"{joint.name} has {len(joint.end_sites)} End Sites, {twin.name} {len(twin.end_sites)}")
    pairs.extend(zip(joint.end_sites, twin.end_sites))
    return pairs


def signs_fit_offsets(signs, pairs):
    for mine, theirs in pairs:
        tolerance = 0.02 * max(np.linalg.norm(mine), np.linalg.norm(theirs)) + 1e-4
        if np.any(np.abs(signs * mine - theirs) > tolerance):
            return False
    return True


def world_mirror_axis(clips, twins):
    """The horizontal axis along which the _L joints lie from their _R twins, in world
    space, averaged over every frame of the clips (its reflection mirrors the world)."""
    totals = np.zeros(3)
    pairs = [(i, t) for i, t in enumerate(twins) if t != i and clips[0].joints[i].name.endswith("_L")]
    for clip in clips:
        positions = forward_kinematics(clip.joints, clip.data[::4])
        lateral = sum(positions[:, i] - positions[:, t] for i, t in pairs)
        totals += np.abs(lateral).sum(axis=0)
    return int(np.argmax(totals))


def plan_mirror(clips):
    """Work out the per-channel mirror mapping of the skeleton the clips share."""
    joints = clips[0].joints
    names = {j.name: i for i, j in enumerate(joints)}
    twins = []
    for joint in joints:
        twin = twin_name(joint.name)
        if twin not in names:
            raise LibraryError(f"{clips[0].path}: joint {joint.name} has no twin {twin} to swap with")
        twins.append(names[twin])
    if all(t == i for i, t in enumerate(twins)):
        raise LibraryError(f"{clips[0].path}: no joint names end in _L or _R; nothing tells left from right")
    for index, joint in enumerate(joints):
        twin = joints[twins[index]]
        if sorted(joint.channels) != sorted(twin.channels):
            raise LibraryError(f"{clips[0].path}: {joint.name} has channels {' '.join(joint.channels)}, "
                               f"its twin {twin.name} {' '.join(twin.channels)}")
        if joint.rotation_axes() != twin.rotation_axes():
            raise LibraryError(f"{clips[0].path}: {joint.name} rotates in order {''.join(joint.rotation_axes())}, "
                               f"its twin {twin.name} in {''.join(twin.rotation_axes())}; "
                               "mirroring needs one order per pair")
        if (joint.parent < 0) != (twin.parent < 0) or (
                joint.parent >= 0 and twins[joint.parent] != twin.parent):
            raise LibraryError(f"{clips[0].path}: {joint.name} and {twin.name} hang from joints that are not twins")

    axis = world_mirror_axis(clips, twins)
    world = np.ones(3)
    world[axis] = -1.0
    offsets, moving = effective_offsets(clips)
    all_data = np.concatenate([c.data for c in clips])
    mean_rotation = [r.mean(axis=0) for r in local_transforms(joints, all_data)[0]]

    signs = [None] * len(joints)
    notes = [f"world: reflect {AXES[axis]} (the _L joints lie from their _R twins along world {AXES[axis]})"]
    for index, joint in enumerate(joints):  # parents come before children
        parent_signs = world if joint.parent < 0 else signs[joint.parent]
        twin = twins[index]
        pairs = offset_constraints(index, joints, twins, offsets, moving)
        fitting = [s for s in SIGN_CANDIDATES if signs_fit_offsets(s, pairs)]
        if not fitting:
            raise LibraryError(f"{clips[0].path}: the offsets below {joint.name} and {joints[twin].name} "
                               "are not mirror images under any axis sign flip")
        if index > twin:
            # The twin was planned first; the pair shares one reflection.
            signs[index] = signs[twin]
            continue
        scores = [np.linalg.norm(mean_rotation[twin] - parent_signs[:, None] * mean_rotation[index] * s[None, :])
                  for s in fitting]
        best = int(np.argmin(scores))
        signs[index] = fitting[best]
        pair = joint.name if twin == index else f"{joint.name}/{joints[twin].name}"
        how = "offsets" if len(fitting) == 1 else (
            "motion: " + ", ".join(f"{describe_signs(s)} {v:.2f}" for s, v in zip(fitting, scores)))
        notes.append(f"{pair}: {describe_signs(signs[index])} ({how})")
        if twin != index and not signs_fit_offsets(signs[index], offset_constraints(twin, joints, twins, offsets, moving)):
            raise LibraryError(f"{clips[0].path}: {joints[twin].name}'s offsets do not mirror {joint.name}'s")

    columns = sum(len(j.channels) for j in joints)
    source = np.arange(columns)
    scale, shift = np.ones(columns), np.zeros(columns)
    for index, joint in enumerate(joints):
        target = joints[twins[index]]
        parent_signs = world if joint.parent < 0 else signs[joint.parent]
        own = signs[index]
        # Positions: t' = S_p t.
        for channel in joint.channels:
            if channel.endswith("position"):
                column = target.column(channel)
                source[column] = joint.column(channel)
                scale[column] = parent_signs[AXES.index(channel[0])]
        # Rotations: R' = S_p R S = (S_p S)(S R S). Conjugating by S (det -1) turns the
        # angle about axis a into -S[a] times it; S_p S is the identity or a half turn about
        # the axis k where S_p and S agree, which a premultiplied sequence absorbs exactly.
        order = joint.rotation_axes()
        angle_scale = {a: -own[AXES.index(a)] for a in order}
        angle_shift = {a: 0.0 for a in order}
        half_turn = parent_signs * own
        if (half_turn < 0).any():
            k = AXES[int(np.argmax(half_turn))]
            if k not in order:
                raise LibraryError(f"{clips[0].path}: mirroring {joint.name} needs a half turn about {k}, "
                                   f"which its rotation channels ({''.join(order)}) cannot hold")
            # R_k(180) R_a(t) = R_a(-t) R_k(180) for a perpendicular to k: the half turn
            # passes the angles before axis k, negating them, and adds 180 degrees there.
            for a in order[:order.index(k)]:
                angle_scale[a] = -angle_scale[a]
                angle_shift[a] = -angle_shift[a]
            angle_shift[k] += 180.0
        for a in order:
            column = target.column(a + "rotation")
            source[column] = joint.column(a + "rotation")
            scale[column] = angle_scale[a]
            shift[column] = angle_shift[a]
    return MirrorPlan(source, scale, shift, world, signs, notes)


# ---------------------------------------------------------------------------------------
# The library


@dataclass
class Copy:
    clip: Clip
    speed: float
    mirrored: bool

    def stem(self):
        parts = []
        if self.speed != 1.0:
            parts.append(f"w{self.speed:.2f}")
        if self.mirrored:
            parts.append("m")
        return f"{self.clip.path.stem}__{'_'.join(parts)}"


def speed_grid():
    return [round(SPEED_MIN + 0.01 * i, 2) for i in range(int(round((SPEED_MAX - SPEED_MIN) / 0.01)) + 1)]


def variants_per_clip(mirrorable):
    return len(speed_grid()) * (2 if mirrorable else 1) - 1


def most_hours(clips, mirrorable):
    """Duration of the originals plus every distinct copy: the longest library possible."""
    seconds = 0.0
    for clip in clips:
        warped = sum(warped_frame_count(clip.frames, s) * clip.frame_time for s in speed_grid())
        # The grid's 1.00 unmirrored is the original itself, counted once.
        seconds += warped * (2 if mirrorable else 1)
    return seconds / 3600.0


def draw_copy(rng, clip, used, mirrorable):
    """A variant of clip not used before: speed log-uniform in 0.80..1.25, mirror 50 %."""
    while True:
        speed = round(math.exp(rng.uniform(math.log(SPEED_MIN), math.log(SPEED_MAX))), 2)
        speed = min(max(speed, SPEED_MIN), SPEED_MAX)
        mirrored = mirrorable and rng.random() < 0.5
        key = (clip.path.name, speed, mirrored)
        if (speed != 1.0 or mirrored) and key not in used:
            used.add(key)
            return Copy(clip, speed, mirrored)


def plan_library(clips, hours, seed, mirrorable):
    """The files to write: (name, clip, copy or None, frames to keep or None)."""
    target = hours * 3600.0
    rng = random.Random(seed)
    used = set()
    total = 0.0
    entries = []

    def add(name, clip, copy, frames):
        nonlocal total
        seconds_left = target - total
        needed = math.ceil(seconds_left / clip.frame_time - 1e-9)
        floor = min(frames, max(2, int(round(1.0 / clip.frame_time))))
        keep = max(needed, floor)
        if keep < frames:
            entries.append((f"{name}_cut{keep}", clip, copy, keep))
            total += keep * clip.frame_time
        else:
            entries.append((name, clip, copy, None))
            total += frames * clip.frame_time
        return total >= target - 1e-9

    for clip in clips:
        if add(clip.path.stem, clip, None, clip.frames):
            return entries
    while True:
        for clip in clips:
            copy = draw_copy(rng, clip, used, mirrorable)
            frames = warped_frame_count(clip.frames, copy.speed)
            if add(copy.stem(), clip, copy, frames):
                return entries


def render(entry, plans):
    """The bytes or text of one planned file."""
    name, clip, copy, keep = entry
    if copy is None and keep is None:
        return clip.path.read_bytes()
    data = clip.data
    if copy is not None:
        if copy.mirrored:
            data = plans[clip.signature()].apply(data)
        if copy.speed != 1.0:
            data = time_warp(data, clip.joints, copy.speed)
    if keep is not None:
        data = data[:keep]
    return format_motion(clip, data)


def default_source():
    data = os.environ.get("MGRL_DATA")
    if not data:
        local = pathlib.Path.home() / ".local/share/mgrl"
        data = str(local) if local.is_dir() else str(ROOT.parent / "shared" / "mocap")
    return pathlib.Path(data) / "bandai_namco_1" / "data"


def prepare_output(out, force):
    if out.exists() and not out.is_dir():
        raise LibraryError(f"{out}: expected a folder to write into, found a file")
    if out.is_dir() and any(out.iterdir()):
        if not force:
            raise LibraryError(f"{out}: expected an empty or new folder, found files in it (pass --force to replace its .bvh files)")
        for old in out.iterdir():
            if old.is_file() and (old.suffix == ".bvh" or old.name.endswith(".tmp")):
                old.unlink()
    out.mkdir(parents=True, exist_ok=True)


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Write a BVH library of a chosen length: the source clips, then time-warped "
                    "and left-right mirrored copies of them, until the total reaches --hours.")
    parser.add_argument("--hours", type=float, required=True, help="total duration to reach (hours, > 0)")
    parser.add_argument("--out", type=pathlib.Path, required=True, help="folder to write (new or empty)")
    parser.add_argument("--source", type=pathlib.Path, default=None,
                        help="folder of source .bvh clips (default: MGRL_DATA, else ~/.local/share/mgrl "
                             "if it exists, else ../shared/mocap; then bandai_namco_1/data)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the speed and mirror draws (default 1)")
    parser.add_argument("--force", action="store_true", help="write into a non-empty --out, first deleting its .bvh files")
    parser.add_argument("--show-mirror", action="store_true", help="print the reflection found for each joint on stderr")
    args = parser.parse_args(argv)
    if not (math.isfinite(args.hours) and args.hours > 0):
        raise LibraryError(f"--hours: expected a positive number of hours, found {args.hours:g}")
    if args.source is None:
        args.source = default_source()
    return args


def main(argv=None):
    args = parse_arguments(argv)
    if not args.source.is_dir():
        raise LibraryError(f"{args.source}: expected a folder of .bvh files, found {'a file' if args.source.exists() else 'nothing'}")
    paths = sorted(p for p in args.source.iterdir() if p.suffix.lower() == ".bvh" and p.is_file())
    if not paths:
        raise LibraryError(f"{args.source}: expected .bvh files, found none")
    if args.out.resolve() == args.source.resolve():
        raise LibraryError(f"{args.out}: expected an output folder other than the source folder")
    clips = [read_bvh(p) for p in paths]

    groups = {}
    for clip in clips:
        groups.setdefault(clip.signature(), []).append(clip)
    plans, mirrorable = {}, True
    for signature, members in groups.items():
        try:
            plans[signature] = plan_mirror(members)
        except LibraryError as err:
            print(f"make_library: not mirroring: {err}", file=sys.stderr)
            mirrorable = False
    if args.show_mirror:
        for plan in plans.values():
            for note in plan.notes:
                print(f"make_library: mirror {note}", file=sys.stderr)

    longest = most_hours(clips, mirrorable)
    if args.hours > longest:
        raise LibraryError(f"{args.source}: --hours {args.hours:g} is more than the {longest:.1f} hours its clips "
                           f"and their {variants_per_clip(mirrorable)} distinct copies each can make")

    entries = plan_library(clips, args.hours, args.seed, mirrorable)
    prepare_output(args.out, args.force)
    target = args.hours * 3600.0
    seconds = frames = mirrored = warped = 0
    next_report = 0.1
    for written, entry in enumerate(entries, 1):
        content = render(entry, plans)
        name, clip, copy, keep = entry
        write_atomically(args.out / f"{name}.bvh", content)
        count = keep if keep is not None else (
            clip.frames if copy is None else warped_frame_count(clip.frames, copy.speed))
        frames += count
        seconds += count * clip.frame_time
        if copy is not None:
            mirrored += copy.mirrored
            warped += copy.speed != 1.0
        while seconds >= next_report * target - 1e-9 and next_report <= 1.0 + 1e-9:
            print(f"make_library: {next_report:4.0%} ({seconds / 3600:.2f} of {args.hours:g} h, "
                  f"{written} files)", file=sys.stderr, flush=True)
            next_report += 0.1

    originals = sum(1 for e in entries if e[2] is None)
    name, clip, copy, keep = entries[-1]
    if keep is not None:
        full = clip.frames if copy is None else warped_frame_count(clip.frames, copy.speed)
        last = f"last file {name}.bvh cut to {keep} of its {full} frames"
    else:
        last = f"last file {name}.bvh whole"
    print(f"make_library: {len(entries)} files, {frames} frames, {seconds / 3600:.4f} hours in {args.out} "
          f"({originals} originals, {len(entries) - originals} copies: {mirrored} mirrored, {warped} time-warped; {last})")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except LibraryError as err:
        print(f"make_library: error: {err}", file=sys.stderr)
        sys.exit(1)
