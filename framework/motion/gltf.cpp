#include "mgrl/motion/gltf.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"

namespace mgrl {
namespace {

using json = nlohmann::json;

// glTF 2.0 constants (specification sec. 3.6.2 and 4.4 "GLB File Format").
constexpr std::uint32_t kGlbMagic = 0x46546C67;     // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;    // "JSON"
constexpr std::uint32_t kChunkBinary = 0x004E4942;  // "BIN\0"
constexpr int kFloat = 5126, kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr double kMaxGlbBytes = 2e9;

// The binary chunk and the JSON that describes it, built together: each add*() appends one
// accessor's data (4-byte aligned, as accessors of 4-byte components must be) with its
// buffer view and returns the accessor's index.
class GlbBuilder {
 public:
  json doc = json::object();

  GlbBuilder() {
    doc["bufferViews"] = json::array();
    doc["accessors"] = json::array();
  }

  template <class T>
  int add(const std::vector<T>& values, int componentType, const char* type, std::size_t count, int target,
          json extra = json::object()) {
    const std::size_t bytes = values.size() * sizeof(T);
    const std::size_t offset = binary.size();
    binary.resize(offset + bytes);
    if (bytes) std::memcpy(binary.data() + offset, values.data(), bytes);
    while (binary.size() % 4) binary.push_back('\0');
    json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
    if (target) view["target"] = target;
    doc["bufferViews"].push_back(view);
    json accessor = {{"bufferView", doc["bufferViews"].size() - 1},
                     {"componentType", componentType},
                     {"count", count},
                     {"type", type}};
    accessor.update(extra);
    doc["accessors"].push_back(accessor);
    return static_cast<int>(doc["accessors"].size() - 1);
  }

  std::string finish() {
    doc["buffers"] = json::array({{{"byteLength", binary.size()}}});
    std::string text = doc.dump();
    while (text.size() % 4) text.push_back(' ');
    const std::size_t total = 12 + 8 + text.size() + 8 + binary.size();
    if (static_cast<double>(total) > kMaxGlbBytes)
      throw Error(fmt::format("glTF: expected a file of at most 2 GB, found {:.2f} GB of data: export fewer frames",
                              static_cast<double>(total) / 1e9));
    std::string out;
    out.reserve(total);
    auto put = [&out](std::uint32_t v) {
      for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));  // little-endian
    };
    put(kGlbMagic);
    put(2);
    put(static_cast<std::uint32_t>(total));
    put(static_cast<std::uint32_t>(text.size()));
    put(kChunkJson);
    out += text;
    put(static_cast<std::uint32_t>(binary.size()));
    put(kChunkBinary);
    out += binary;
    return out;
  }

 private:
  std::string binary;
};

// Each component's smallest (`largest` false) or largest value of `values`, `width` floats
// an element: what an accessor's "min" or "max" must say.
json bound(const std::vector<float>& values, int width, bool largest) {
  json out = json::array();
  for (int c = 0; c < width; ++c) {
    float v = largest ? std::numeric_limits<float>::lowest() : std::numeric_limits<float>::max();
    for (std::size_t i = static_cast<std::size_t>(c); i < values.size(); i += static_cast<std::size_t>(width))
      v = largest ? std::max(v, values[i]) : std::min(v, values[i]);
    out.push_back(v);
  }
  return out;
}

// The body: capsules around bones, each rigidly bound to one joint.
struct BodyMesh {
  std::vector<float> positions, normals, colors, weights;
  std::vector<std::uint16_t> joints;
  std::vector<std::uint32_t> indices;

  // A capsule of `radius` around the segment a -> b, bound to `joint`.
  void capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, int joint,
               const Eigen::Vector3f& color, int segments, int capRings) {
    const Eigen::Vector3d axis = (b - a).normalized();
    // Any two unit vectors perpendicular to the axis and to each other.
    const Eigen::Vector3d helper = std::abs(axis.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d u = axis.cross(helper).normalized();
    const Eigen::Vector3d v = axis.cross(u);
    const auto first = static_cast<std::uint32_t>(positions.size() / 3);
    auto vertex = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
      for (int c = 0; c < 3; ++c) {
        positions.push_back(static_cast<float>(p[c]));
        normals.push_back(static_cast<float>(n[c]));
        colors.push_back(color[c]);
      }
      joints.insert(joints.end(), {static_cast<std::uint16_t>(joint), 0, 0, 0});
      weights.insert(weights.end(), {1.0f, 0.0f, 0.0f, 0.0f});
    };
    // Rings from the bottom half sphere (around a) to the top one (around b), between the
    // two poles; latitude phi in (-90, 90) degrees.
    std::vector<std::pair<double, bool>> rings;  // (phi, on the top half)
    for (int k = 1; k <= capRings; ++k) rings.push_back({-M_PI / 2 + M_PI / 2 * k / capRings, false});
    for (int k = 0; k < capRings; ++k) rings.push_back({M_PI / 2 * k / capRings, true});
    vertex(a - radius * axis, -axis);
    for (const auto& [phi, top] : rings) {
      const Eigen::Vector3d centre = (top ? b : a) + radius * std::sin(phi) * axis;
      for (int s = 0; s < segments; ++s) {
        const double theta = 2 * M_PI * s / segments;
        const Eigen::Vector3d radial = std::cos(theta) * u + std::sin(theta) * v;
        vertex(centre + radius * std::cos(phi) * radial, std::cos(phi) * radial + std::sin(phi) * axis);
      }
    }
    vertex(b + radius * axis, axis);
    const auto ringCount = static_cast<std::uint32_t>(rings.size());
    const auto n = static_cast<std::uint32_t>(segments);
    const std::uint32_t bottom = first, top = first + 1 + ringCount * n;
    auto ring = [&](std::uint32_t r, std::uint32_t s) { return first + 1 + r * n + s % n; };
    auto triangle = [&](std::uint32_t i, std::uint32_t j, std::uint32_t k) {
      // Counter-clockwise seen from outside (glTF's front face): flip where the vertex
      // normals say the winding points inward.
      auto p = [&](std::uint32_t x) {
        return Eigen::Vector3d(positions[3 * x], positions[3 * x + 1], positions[3 * x + 2]);
      };
      auto nrm = [&](std::uint32_t x) {
        return Eigen::Vector3d(normals[3 * x], normals[3 * x + 1], normals[3 * x + 2]);
      };
      const Eigen::Vector3d face = (p(j) - p(i)).cross(p(k) - p(i));
      if (face.dot(nrm(i) + nrm(j) + nrm(k)) < 0) std::swap(j, k);
      indices.insert(indices.end(), {i, j, k});
    };
    for (std::uint32_t s = 0; s < n; ++s) {
      triangle(bottom, ring(0, s), ring(0, s + 1));
      for (std::uint32_t r = 0; r + 1 < ringCount; ++r) {
        triangle(ring(r, s), ring(r + 1, s), ring(r + 1, s + 1));
        triangle(ring(r, s), ring(r + 1, s + 1), ring(r, s + 1));
      }
      triangle(top, ring(ringCount - 1, s + 1), ring(ringCount - 1, s));
    }
  }
};

std::vector<float> floats(std::initializer_list<double> values) {
  std::vector<float> out;
  for (double v : values) out.push_back(static_cast<float>(v));
  return out;
}

// The body mesh, in the bind pose (`rest`: each joint's position): a capsule per bone.
void addBodyMesh(GlbBuilder& glb, const Skeleton& skeleton, const std::vector<Eigen::Vector3d>& rest,
                 const GltfWriteOptions& options) {
  json& doc = glb.doc;
  const std::size_t jointCount = skeleton.jointCount();
  BodyMesh body;
  std::vector<Eigen::Vector3f> color(jointCount, options.bodyColor);
  for (const auto& [j, c] : options.jointColors)
    if (j >= 0 && static_cast<std::size_t>(j) < jointCount) color[static_cast<std::size_t>(j)] = c;
  auto bone = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, std::size_t joint) {
    const double length = (b - a).norm();
    if (!(length >= options.minBoneLength)) return;
    const auto own = options.jointRadii.find(static_cast<int>(joint));
    const double radius = own != options.jointRadii.end() && own->second > 0
                              ? own->second
                              : std::clamp(options.radiusPerLength * length, options.minRadius, options.maxRadius);
    body.capsule(a, b, radius, static_cast<int>(joint), color[joint], options.segments, options.capRings);
  };
  for (std::size_t j = 1; j < jointCount; ++j) {
    const auto parent = static_cast<std::size_t>(skeleton.joint(j).parent);
    bone(rest[parent], rest[j], parent);
  }
  for (std::size_t j = 0; j < jointCount; ++j)
    if (skeleton.joint(j).endSite) bone(rest[j], rest[j] + *skeleton.joint(j).endSite, j);
  if (body.positions.empty())  // a skeleton of one joint, or of bones too short: a ball at the root
    body.capsule(rest[0], rest[0] + Eigen::Vector3d(0, options.minBoneLength, 0), options.maxRadius, 0,
                 options.bodyColor, options.segments, options.capRings);
  const std::size_t vertices = body.positions.size() / 3;
  json attributes = {
      {"POSITION", glb.add(body.positions, kFloat, "VEC3", vertices, kArrayBuffer,
                           {{"min", bound(body.positions, 3, false)}, {"max", bound(body.positions, 3, true)}})},
      {"NORMAL", glb.add(body.normals, kFloat, "VEC3", vertices, kArrayBuffer)},
      {"COLOR_0", glb.add(body.colors, kFloat, "VEC3", vertices, kArrayBuffer)},
      {"JOINTS_0", glb.add(body.joints, kUnsignedShort, "VEC4", vertices, kArrayBuffer)},
      {"WEIGHTS_0", glb.add(body.weights, kFloat, "VEC4", vertices, kArrayBuffer)}};
  int indices;
  if (vertices <= 65535) {
    std::vector<std::uint16_t> shortIndices(body.indices.begin(), body.indices.end());
    indices = glb.add(shortIndices, kUnsignedShort, "SCALAR", shortIndices.size(), kElementArrayBuffer);
  } else {
    indices = glb.add(body.indices, kUnsignedInt, "SCALAR", body.indices.size(), kElementArrayBuffer);
  }
  doc["materials"] =
      json::array({{{"name", "body"},
                    {"pbrMetallicRoughness",
                     {{"baseColorFactor", {1.0, 1.0, 1.0, 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.8}}}}});
  doc["meshes"] = json::array(
      {{{"name", options.name},
        {"primitives", json::array({{{"attributes", attributes}, {"indices", indices}, {"material", 0}}})}}});
}

// The animation: one key per frame, LINEAR; a rotation channel per joint and a
// translation channel per translated joint.
void addAnimation(GlbBuilder& glb, const Motion& motion, const GltfWriteOptions& options) {
  json& doc = glb.doc;
  const Skeleton& skeleton = motion.skeleton();
  const std::size_t jointCount = skeleton.jointCount();
  const std::size_t frames = motion.frameCount();
  std::vector<float> times(frames);
  for (std::size_t f = 0; f < frames; ++f) times[f] = static_cast<float>(static_cast<double>(f) * motion.frameTime());
  const int input = glb.add(times, kFloat, "SCALAR", frames, 0,
                            {{"min", json::array({times.front()})}, {"max", json::array({times.back()})}});
  json samplers = json::array(), channels = json::array();
  auto channel = [&](int output, std::size_t joint, const char* path) {
    samplers.push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
    channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", joint + 1}, {"path", path}}}});
  };
  std::vector<float> values;
  for (std::size_t j = 0; j < jointCount; ++j) {
    values.clear();
    values.reserve(4 * frames);
    Eigen::Quaterniond previous = Eigen::Quaterniond::Identity();
    for (std::size_t f = 0; f < frames; ++f) {
      Eigen::Quaterniond q = motion.rotation(f, j).normalized();
      // The same hemisphere as the frame before, so that interpolation takes the short way.
      if (f > 0 && q.coeffs().dot(previous.coeffs()) < 0) q.coeffs() = -q.coeffs();
      previous = q;
      values.insert(values.end(), {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()),
                                   static_cast<float>(q.w())});
    }
    channel(glb.add(values, kFloat, "VEC4", frames, 0), j, "rotation");
    if (skeleton.translationSlot(j) >= 0) {
      values.clear();
      for (std::size_t f = 0; f < frames; ++f) {
        const Eigen::Vector3d t = motion.localTranslation(f, j);
        values.insert(values.end(), {static_cast<float>(t.x()), static_cast<float>(t.y()), static_cast<float>(t.z())});
      }
      channel(glb.add(values, kFloat, "VEC3", frames, 0), j, "translation");
    }
  }
  doc["animations"] = json::array({{{"name", options.name}, {"samplers", samplers}, {"channels", channels}}});
}

}  // namespace

std::string writeGlb(const Motion& motion, const GltfWriteOptions& options) {
  const Skeleton& skeleton = motion.skeleton();
  const std::size_t jointCount = skeleton.jointCount();
  const std::size_t frames = motion.frameCount();
  if (jointCount > 65535)
    throw Error(
        fmt::format("glTF: expected at most 65535 joints (a skin's joint indices are 16 bits), found {}", jointCount));
  if (options.segments < 3 || options.capRings < 1)
    throw Error(fmt::format("glTF: expected at least 3 segments and 1 ring per capsule cap, found {} and {}",
                            options.segments, options.capRings));
  // Before any allocation that grows with the motion: the animation's size.
  const double animationBytes =
      static_cast<double>(frames) *
      (4.0 + 16.0 * static_cast<double>(jointCount) + 12.0 * static_cast<double>(skeleton.translatedJoints().size()));
  if (animationBytes > kMaxGlbBytes)
    throw Error(
        fmt::format("glTF: expected a file of at most 2 GB, found {} frames of {} joints ({:.2f} GB): export "
                    "fewer frames",
                    frames, jointCount, animationBytes / 1e9));
  GlbBuilder glb;
  json& doc = glb.doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", options.generator}};

  // Rest (bind) pose: identity rotations, so a joint's global position is the sum of the
  // offsets down to it, and its inverse bind matrix a translation back.
  std::vector<Eigen::Vector3d> rest(jointCount);
  for (std::size_t j = 0; j < jointCount; ++j) {
    const int parent = skeleton.joint(j).parent;
    rest[j] =
        (parent < 0 ? Eigen::Vector3d::Zero() : rest[static_cast<std::size_t>(parent)]) + skeleton.joint(j).offset;
  }

  // Nodes: the body, then one per joint at its frame-0 pose.
  json nodes = json::array();
  nodes.push_back({{"name", "body"}, {"mesh", 0}, {"skin", 0}});
  std::vector<json> children(jointCount, json::array());
  for (std::size_t j = 1; j < jointCount; ++j)
    children[static_cast<std::size_t>(skeleton.joint(j).parent)].push_back(j + 1);
  for (std::size_t j = 0; j < jointCount; ++j) {
    const Eigen::Vector3d t = motion.localTranslation(0, j);
    const Eigen::Quaterniond q = motion.rotation(0, j).normalized();
    json node = {{"name", skeleton.joint(j).name},
                 {"translation", floats({t.x(), t.y(), t.z()})},
                 {"rotation", floats({q.x(), q.y(), q.z(), q.w()})}};
    if (!children[j].empty()) node["children"] = children[j];
    nodes.push_back(node);
  }
  doc["nodes"] = nodes;
  doc["scene"] = 0;
  doc["scenes"] = json::array({{{"name", options.name}, {"nodes", {0, 1}}}});

  // The skin.
  std::vector<float> inverseBind;
  inverseBind.reserve(16 * jointCount);
  for (std::size_t j = 0; j < jointCount; ++j) {
    // Column-major 4x4: identity with the translation -rest in the last column.
    const Eigen::Vector3d& p = rest[j];
    for (double v : {1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -p.x(), -p.y(), -p.z(), 1.0})
      inverseBind.push_back(static_cast<float>(v));
  }
  json skinJoints = json::array();
  for (std::size_t j = 0; j < jointCount; ++j) skinJoints.push_back(j + 1);
  const int ibm = glb.add(inverseBind, kFloat, "MAT4", jointCount, 0);
  doc["skins"] =
      json::array({{{"name", options.name}, {"joints", skinJoints}, {"skeleton", 1}, {"inverseBindMatrices", ibm}}});

  addBodyMesh(glb, skeleton, rest, options);
  addAnimation(glb, motion, options);
  return glb.finish();
}

GlbParts splitGlb(std::string_view bytes, std::string_view source) {
  auto word = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
    return v;
  };
  if (bytes.size() < 20)
    throw Error(fmt::format("{}: expected a binary glTF of at least 20 bytes, found {}", source, bytes.size()));
  if (word(0) != kGlbMagic)
    throw Error(fmt::format("{}: expected the binary glTF magic 'glTF', found 0x{:08x}", source, word(0)));
  if (word(4) != 2) throw Error(fmt::format("{}: expected glTF version 2, found {}", source, word(4)));
  if (word(8) != bytes.size())
    throw Error(fmt::format("{}: expected the header's length {} to be the file's, found {} bytes", source, word(8),
                            bytes.size()));
  GlbParts parts;
  std::size_t at = 12;
  for (int chunk = 0; at < bytes.size(); ++chunk) {
    if (bytes.size() - at < 8)
      throw Error(fmt::format("{}: expected a chunk header at byte {}, found {} bytes", source, at, bytes.size() - at));
    const std::uint32_t length = word(at), type = word(at + 4);
    if (length > bytes.size() - at - 8)
      throw Error(fmt::format("{}: expected chunk {} ({} bytes) to end within the file, found {} bytes left", source,
                              chunk, length, bytes.size() - at - 8));
    const std::string_view body = bytes.substr(at + 8, length);
    if (chunk == 0 && type != kChunkJson)
      throw Error(fmt::format("{}: expected the first chunk to be JSON, found type 0x{:08x}", source, type));
    if (chunk == 0) parts.json = body;
    if (chunk == 1 && type == kChunkBinary) parts.binary = body;
    at += 8 + length;
  }
  return parts;
}

}  // namespace mgrl
