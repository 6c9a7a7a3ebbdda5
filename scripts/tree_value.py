#!/usr/bin/env python3
"""Rebuild a kd_tree behaviour of a policy bundle with NumPy and interpolate its Q values.

    scripts/tree_value.py BUNDLE BEHAVIOUR X Y Z [X Y Z ...] [--action A]

For each target position (X, Y, Z) in the avatar frame (metres: +Z ahead, +X left, Y up)
it prints one line: the leaf the point falls in and max_a Q(e, a) over every action of
the table (or Q(e, A) with --action), interpolated multilinearly from the leaf's corners,
or "outside" when the point is off the tree (future value 0 there, paper sec. 4.2).

It reads only the bundle's arrays (framework/include/mgrl/learning/policy_bundle.hpp): the tree
(`<b>.grid.split_axis/split_value/children/leaf_corners/bounds[/roots].npy`) and the table
(`<b>.q.npy`, one row per action). It is the worked answer to "can NumPy rebuild the
tree?", and the reference a test compares mgrl's own interpolation with; see
discretizers/README.md for what the arrays mean. Needs NumPy (Debian: python3-numpy).
"""
import argparse
import json
import math
import os
import sys

import numpy as np


class Tree:
    """A kd_tree from its saved arrays: a forest of root boxes split at stored values."""

    def __init__(self, bundle, behaviour):
        with open(os.path.join(bundle, "manifest.json")) as f:
            entry = json.load(f)["behaviors"][behaviour]
        grid = entry.get("grid")
        if not grid or grid.get("type") != "kd_tree":
            sys.exit(f"tree_value: {behaviour} in {bundle}: expected a kd_tree grid, found {grid and grid.get('type')}")

        def array(name):
            return np.load(os.path.join(bundle, f"{behaviour}.grid.{name}.npy"))

        self.axis = array("split_axis")
        self.value = array("split_value")
        self.children = array("children")
        self.corners = array("leaf_corners")
        self.bounds = array("bounds")
        self.dims = self.bounds.shape[0]
        self.roots = array("roots") if "roots" in grid["arrays"] else np.ones(self.dims, dtype=np.int32)
        self.q = np.load(os.path.join(bundle, entry["table"]["file"]))  # (actions, vertices)
        # A full turn of angle wraps (the bounds then span 2 pi).
        self.wraps = [i == 0 and self.dims > 1 and self.bounds[0, 1] - self.bounds[0, 0] >= 2 * math.pi - 1e-9
                      for i in range(self.dims)]
        # Leaves are numbered depth-first, root by root (first axis fastest), low child first.
        self.leaf = {}
        for root in range(int(np.prod(self.roots))):
            stack = [root]
            while stack:
                n = stack.pop()
                if self.axis[n] < 0:
                    self.leaf[n] = len(self.leaf)
                else:
                    stack += [self.children[n, 1], self.children[n, 0]]

    def coordinates(self, x, y, z):
        """Grid coordinates of an avatar-frame position, as the discretizer computes them."""
        angle, distance = math.atan2(x, z), math.hypot(x, z)
        if self.dims == 1:
            return [math.copysign(distance, z)]
        return [angle, distance] + ([y] if self.dims == 3 else [])

    def locate(self, c):
        """(leaf, fractions) of grid coordinates c, or None outside the tree."""
        lo, hi = self.bounds[:, 0].copy(), self.bounds[:, 1].copy()
        root, stride = 0, 1
        for i in range(self.dims):
            if self.wraps[i]:
                c[i] = lo[i] + (c[i] - lo[i]) % (2 * math.pi)
            elif not lo[i] <= c[i] <= hi[i]:
                return None
            step = (hi[i] - lo[i]) / self.roots[i]
            j = min(int((c[i] - lo[i]) / step), self.roots[i] - 1)
            lo[i], hi[i] = lo[i] + step * j, lo[i] + step * (j + 1)
            root += j * stride
            stride *= self.roots[i]
        n = root
        while self.axis[n] >= 0:
            a, split = self.axis[n], self.value[n]
            if c[a] >= split:
                n, lo[a] = self.children[n, 1], split
            else:
                n, hi[a] = self.children[n, 0], split
        frac = [min(max((c[i] - lo[i]) / (hi[i] - lo[i]), 0.0), 1.0) for i in range(self.dims)]
        return self.leaf[n], frac

    def interpolate(self, leaf, frac, action=None):
        """Q(e, action), or max over actions, from the leaf's 2^d corners."""
        total = np.zeros(self.q.shape[0])
        for k in range(1 << self.dims):
            w = 1.0
            for i in range(self.dims):
                w *= frac[i] if (k >> i) & 1 else 1 - frac[i]
            total += w * self.q[:, self.corners[leaf, k]]
        return total[action] if action is not None else total.max()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bundle")
    parser.add_argument("behaviour")
    parser.add_argument("xyz", nargs="+", type=float, help="target positions, three numbers each")
    parser.add_argument("--action", type=int, default=None)
    args = parser.parse_args()
    if len(args.xyz) % 3:
        sys.exit(f"tree_value: expected positions of three numbers (X Y Z), found {len(args.xyz)} numbers")
    tree = Tree(args.bundle, args.behaviour)
    for p in range(0, len(args.xyz), 3):
        found = tree.locate(tree.coordinates(*args.xyz[p:p + 3]))
        if found is None:
            print("outside")
        else:
            print(found[0], repr(float(tree.interpolate(*found, action=args.action))))


if __name__ == "__main__":
    main()
