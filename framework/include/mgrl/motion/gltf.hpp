#pragma once
/// \file
/// glTF 2.0 writing: a motion as a binary glTF (`.glb`) that game engines,
/// three.js and Blender load: the skeleton as a tree of nodes, one animation whose channels
/// give every joint its rotation (and the joints with position channels their translation)
/// at each frame, and a skinned body of capsules, one per bone, so that the file shows as
/// a figure and not only as joints.
///
/// The file follows the glTF 2.0 specification (Khronos, 2021): metres, Y up, right-handed,
/// which is mgrl's own frame (DESIGN.md), so nothing is converted but the number type.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mgrl/motion/motion.hpp"

namespace mgrl {

struct GltfWriteOptions {
  /// Name of the scene, the animation and the mesh (e.g. "avatar_000").
  std::string name = "mgrl";
  /// The body's colour (linear RGB in [0, 1]).
  Eigen::Vector3f bodyColor{0.55f, 0.60f, 0.68f};
  /// Joints whose bones (from the joint to its children and to its end site) get their own
  /// colour, for instance gloves and shoes, so that hands and feet stand out. Skeleton
  /// indices; others are ignored.
  std::map<int, Eigen::Vector3f> jointColors;
  /// Joints whose bones get this capsule radius (metres) instead of the rule below: the
  /// trunk wider than the limbs, say. Skeleton indices; others are ignored.
  std::map<int, double> jointRadii;
  /// Capsule radius of any other bone: this share of its length, within [minRadius,
  /// maxRadius] (metres); bones shorter than minBoneLength get no capsule.
  double radiusPerLength = 0.2, minRadius = 0.025, maxRadius = 0.075, minBoneLength = 0.01;
  /// Sides around a capsule and rings per half sphere.
  int segments = 10, capRings = 3;
  /// Written as the asset's generator.
  std::string generator = "mgrl";
};

/// Writes `motion` as a binary glTF 2.0 file and returns its bytes:
/// - node 0, "body", holds the skinned mesh and is a root of the scene; nodes 1..J are the
///   skeleton's joints in skeleton order (node j + 1 is joint j, named as the joint), each
///   with its parent's node as parent, the root joint a second root of the scene. Each
///   joint node's translation and rotation are those of frame 0.
/// - one animation, `options.name`, with a LINEAR rotation channel for every joint and a
///   LINEAR translation channel for every joint with position channels, keyed at
///   frame * frameTime seconds; successive quaternions keep the same hemisphere.
/// - a skin over the joint nodes whose bind pose is the skeleton's rest pose (every
///   rotation identity, every translation its offset), and a mesh of one capsule per bone
///   (parent to child joint, and joint to end site), each rigidly bound to its upper joint,
///   coloured by vertex (COLOR_0).
/// Lengths are the motion's own (metres once loaded). Throws mgrl::Error if the motion has
/// more joints than a glTF skin here allows (65535) or the file would pass 2 GB.
std::string writeGlb(const Motion& motion, const GltfWriteOptions& options = {});

/// The parts of a `.glb` file: its JSON text and its binary chunk. Throws mgrl::Error
/// (naming `source`) if the bytes are not a well-formed glTF 2.0 binary container: wrong
/// magic or version, a length that disagrees with the bytes, a chunk that runs past the
/// end, a first chunk that is not JSON. For the tests and for tools that read back what
/// writeGlb wrote; it does not validate the glTF content (gltf-validator does, tests/web).
struct GlbParts {
  std::string json;
  std::string binary;
};
GlbParts splitGlb(std::string_view bytes, std::string_view source);

}  // namespace mgrl
