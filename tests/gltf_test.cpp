// glTF 2.0 export: the .glb that writeGlb() makes is read back here by a small
// independent reader (the container, the accessors, the node tree, the animation), and
// its joints must stand where mgrl's own forward kinematics puts them, frame by frame.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/gltf.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace gltf_test {

using namespace mgrl;
using json = nlohmann::json;

namespace {

struct GlbFile {
  json doc;
  std::string binary;

  // Accessor `index` as floats (FLOAT components) or as integers widened to float.
  std::vector<float> floats(int index) const {
    const json& a = doc["accessors"][index];
    const json& view = doc["bufferViews"][a["bufferView"].get<int>()];
    const std::size_t offset = view.value("byteOffset", 0) + a.value("byteOffset", 0);
    static const std::map<std::string, int> widths = {
        {"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}, {"MAT4", 16}};
    const std::size_t n = a["count"].get<std::size_t>() * widths.at(a["type"].get<std::string>());
    const int type = a["componentType"].get<int>();
    const std::size_t size = type == 5126 || type == 5125 ? 4 : type == 5123 ? 2 : 1;
    REQUIRE(offset + n * size <= view["byteOffset"].get<std::size_t>() + view["byteLength"].get<std::size_t>());
    REQUIRE(offset + n * size <= binary.size());
    std::vector<float> out(n);
    for (std::size_t i = 0; i < n; ++i) {
      const char* p = binary.data() + offset + i * size;
      if (type == 5126) {
        std::memcpy(&out[i], p, 4);
      } else if (type == 5125) {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        out[i] = static_cast<float>(v);
      } else if (type == 5123) {
        std::uint16_t v;
        std::memcpy(&v, p, 2);
        out[i] = v;
      } else {
        out[i] = static_cast<unsigned char>(*p);
      }
    }
    return out;
  }
};

GlbFile readGlb(const std::string& bytes) {
  const GlbParts parts = splitGlb(bytes, "test.glb");
  GlbFile file{json::parse(parts.json), parts.binary};
  REQUIRE(file.doc["buffers"][0]["byteLength"].get<std::size_t>() == file.binary.size());
  return file;
}

// World positions of every joint node at animation key `frame`, from the file alone: each
// node's TRS from its channels (or its own TRS), composed down the node tree.
std::vector<Eigen::Vector3d> glbJointPositions(const GlbFile& f, std::size_t frame) {
  const json& nodes = f.doc["nodes"];
  std::vector<Eigen::Vector3d> t(nodes.size(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Quaterniond> r(nodes.size(), Eigen::Quaterniond::Identity());
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    if (nodes[n].contains("translation"))
      for (int c = 0; c < 3; ++c) t[n][c] = nodes[n]["translation"][c].get<double>();
    if (nodes[n].contains("rotation"))
      r[n] = Eigen::Quaterniond(nodes[n]["rotation"][3].get<double>(), nodes[n]["rotation"][0].get<double>(),
                                nodes[n]["rotation"][1].get<double>(), nodes[n]["rotation"][2].get<double>());
  }
  const json& animation = f.doc["animations"][0];
  for (const json& channel : animation["channels"]) {
    const json& sampler = animation["samplers"][channel["sampler"].get<int>()];
    const std::vector<float> out = f.floats(sampler["output"].get<int>());
    const auto node = channel["target"]["node"].get<std::size_t>();
    if (channel["target"]["path"] == "rotation")
      r[node] = Eigen::Quaterniond(out[4 * frame + 3], out[4 * frame], out[4 * frame + 1], out[4 * frame + 2]);
    else
      t[node] = Eigen::Vector3d(out[3 * frame], out[3 * frame + 1], out[3 * frame + 2]);
  }
  std::vector<int> parent(nodes.size(), -1);
  for (std::size_t n = 0; n < nodes.size(); ++n)
    for (const json& child : nodes[n].value("children", json::array()))
      parent[child.get<std::size_t>()] = static_cast<int>(n);
  std::vector<Eigen::Vector3d> position(nodes.size());
  std::vector<Eigen::Quaterniond> rotation(nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n) {  // parents come first in this file
    if (parent[n] < 0) {
      position[n] = t[n];
      rotation[n] = r[n].normalized();
    } else {
      const auto p = static_cast<std::size_t>(parent[n]);
      REQUIRE(p < n);
      position[n] = position[p] + rotation[p] * t[n];
      rotation[n] = rotation[p] * r[n].normalized();
    }
  }
  return {position.begin() + 1, position.end()};  // node 0 is the body
}

Motion tinyMotion() { return loadMotion(test::testData() / "tiny.bvh").motion; }

}  // namespace

TEST_CASE("writeGlb: the joints of the file stand where forward kinematics puts them, every frame", "[gltf]") {
  const Motion motion = tinyMotion();
  const GlbFile f = readGlb(writeGlb(motion));
  const Skeleton& skeleton = motion.skeleton();
  REQUIRE(f.doc["asset"]["version"] == "2.0");
  REQUIRE(f.doc["nodes"].size() == skeleton.jointCount() + 1);
  for (std::size_t j = 0; j < skeleton.jointCount(); ++j)
    CHECK(f.doc["nodes"][j + 1]["name"] == skeleton.joint(j).name);
  // One rotation channel per joint, one translation channel per joint with position channels.
  CHECK(f.doc["animations"][0]["channels"].size() == skeleton.jointCount() + skeleton.translatedJoints().size());
  // Keys at the capture's rate.
  const std::vector<float> times = f.floats(f.doc["animations"][0]["samplers"][0]["input"].get<int>());
  REQUIRE(times.size() == motion.frameCount());
  CHECK(times[1] == Approx(motion.frameTime()));
  CHECK(times.back() == Approx(motion.frameTime() * static_cast<double>(motion.frameCount() - 1)));

  std::vector<Eigen::Quaterniond> rotations(skeleton.jointCount());
  std::vector<Eigen::Vector3d> positions(skeleton.jointCount());
  double worst = 0;
  for (std::size_t frame = 0; frame < motion.frameCount(); ++frame) {
    forwardKinematics(motion, frame, rotations, positions);
    const std::vector<Eigen::Vector3d> fromFile = glbJointPositions(f, frame);
    for (std::size_t j = 0; j < skeleton.jointCount(); ++j)
      worst = std::max(worst, (fromFile[j] - positions[j]).norm());
  }
  CHECK(worst < 1e-5);  // metres: float precision
}

TEST_CASE("writeGlb: a real capture's joints within a micrometre-scale error, quaternions without flips",
          "[gltf][data]") {
  const Motion motion = test::loadMocap("cmu/bvh/13_17_boxing.bvh").motion.slice(0, 240);
  const GlbFile f = readGlb(writeGlb(motion));
  const Skeleton& skeleton = motion.skeleton();
  std::vector<Eigen::Quaterniond> rotations(skeleton.jointCount());
  std::vector<Eigen::Vector3d> positions(skeleton.jointCount());
  double worst = 0;
  for (std::size_t frame = 0; frame < motion.frameCount(); frame += 7) {
    forwardKinematics(motion, frame, rotations, positions);
    const std::vector<Eigen::Vector3d> fromFile = glbJointPositions(f, frame);
    for (std::size_t j = 0; j < skeleton.jointCount(); ++j)
      worst = std::max(worst, (fromFile[j] - positions[j]).norm());
  }
  CHECK(worst < 1e-4);
  // Successive keys of every rotation channel on the same hemisphere (interpolation takes
  // the short way).
  const json& animation = f.doc["animations"][0];
  for (const json& channel : animation["channels"]) {
    if (channel["target"]["path"] != "rotation") continue;
    const std::vector<float> q = f.floats(animation["samplers"][channel["sampler"].get<int>()]["output"].get<int>());
    for (std::size_t k = 4; k < q.size(); k += 4)
      REQUIRE(q[k] * q[k - 4] + q[k + 1] * q[k - 3] + q[k + 2] * q[k - 2] + q[k + 3] * q[k - 1] >= 0);
  }
}

TEST_CASE("writeGlb: a skinned body in the bind pose, well-formed for a renderer", "[gltf]") {
  const Motion motion = tinyMotion();
  GltfWriteOptions options;
  options.jointColors[motion.skeleton().find("LeftFoot")] = Eigen::Vector3f(1, 0, 0);
  const GlbFile f = readGlb(writeGlb(motion, options));
  const Skeleton& skeleton = motion.skeleton();
  const json& primitive = f.doc["meshes"][0]["primitives"][0];
  const std::vector<float> pos = f.floats(primitive["attributes"]["POSITION"].get<int>());
  const std::vector<float> normal = f.floats(primitive["attributes"]["NORMAL"].get<int>());
  const std::vector<float> color = f.floats(primitive["attributes"]["COLOR_0"].get<int>());
  const std::vector<float> joints = f.floats(primitive["attributes"]["JOINTS_0"].get<int>());
  const std::vector<float> weights = f.floats(primitive["attributes"]["WEIGHTS_0"].get<int>());
  const std::vector<float> indices = f.floats(primitive["indices"].get<int>());
  const std::size_t vertices = pos.size() / 3;
  REQUIRE(vertices > 0);
  REQUIRE(normal.size() == 3 * vertices);
  REQUIRE(joints.size() == 4 * vertices);
  REQUIRE(indices.size() % 3 == 0);
  for (float i : indices) REQUIRE(i < static_cast<float>(vertices));
  // POSITION's min and max are the data's, as the specification requires.
  const json& accessor = f.doc["accessors"][primitive["attributes"]["POSITION"].get<int>()];
  for (int c = 0; c < 3; ++c) {
    float lo = pos[c], hi = pos[c];
    for (std::size_t v = 0; v < vertices; ++v) lo = std::min(lo, pos[3 * v + c]), hi = std::max(hi, pos[3 * v + c]);
    CHECK(accessor["min"][c].get<float>() == lo);
    CHECK(accessor["max"][c].get<float>() == hi);
  }
  std::vector<std::size_t> perJoint(skeleton.jointCount(), 0);
  for (std::size_t v = 0; v < vertices; ++v) {
    const double n = std::sqrt(normal[3 * v] * normal[3 * v] + normal[3 * v + 1] * normal[3 * v + 1] +
                               normal[3 * v + 2] * normal[3 * v + 2]);
    REQUIRE(n == Approx(1).margin(1e-5));
    REQUIRE(weights[4 * v] + weights[4 * v + 1] + weights[4 * v + 2] + weights[4 * v + 3] == Approx(1));
    REQUIRE(joints[4 * v] < static_cast<float>(skeleton.jointCount()));
    ++perJoint[static_cast<std::size_t>(joints[4 * v])];
  }
  // Triangles face outward: the winding agrees with the vertex normals.
  for (std::size_t t = 0; t < indices.size(); t += 3) {
    Eigen::Vector3d p[3], n = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(indices[t + k]);
      p[k] = Eigen::Vector3d(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
      n += Eigen::Vector3d(normal[3 * v], normal[3 * v + 1], normal[3 * v + 2]);
    }
    REQUIRE((p[1] - p[0]).cross(p[2] - p[0]).dot(n) > 0);
  }
  // The hips carry the pelvis and thighs' capsules; the coloured foot's vertices are red.
  CHECK(perJoint[0] > 0);
  const int foot = skeleton.find("LeftFoot");
  std::size_t red = 0;
  for (std::size_t v = 0; v < vertices; ++v)
    if (static_cast<int>(joints[4 * v]) == foot) {
      CHECK(color[3 * v] == 1.0f);
      CHECK(color[3 * v + 1] == 0.0f);
      ++red;
    }
  CHECK(red > 0);
  // Each inverse bind matrix undoes its joint's rest position (the bind pose).
  const std::vector<Eigen::Vector3d> rest = restPositions(skeleton);
  const std::vector<float> ibm = f.floats(f.doc["skins"][0]["inverseBindMatrices"].get<int>());
  REQUIRE(ibm.size() == 16 * skeleton.jointCount());
  for (std::size_t j = 0; j < skeleton.jointCount(); ++j)
    for (int c = 0; c < 3; ++c) CHECK(ibm[16 * j + 12 + c] == Approx(-rest[j][c]).margin(1e-6));
  // The body node is a root of the scene and bound to the skin over every joint node.
  CHECK(f.doc["scenes"][0]["nodes"] == json::array({0, 1}));
  CHECK(f.doc["nodes"][0]["skin"] == 0);
  CHECK(f.doc["skins"][0]["joints"].size() == skeleton.jointCount());
}

TEST_CASE("splitGlb refuses what is not a binary glTF 2.0, saying what and where", "[gltf][errors]") {
  const std::string good = writeGlb(tinyMotion());
  REQUIRE_NOTHROW(splitGlb(good, "a.glb"));
  auto refuses = [](const std::string& bytes, const std::string& detail) {
    CAPTURE(detail);
    REQUIRE_THROWS_WITH(splitGlb(bytes, "a.glb"), Catch::Contains("a.glb: ") && Catch::Contains(detail));
  };
  refuses(good.substr(0, 10), "expected a binary glTF of at least 20 bytes, found 10");
  std::string wrong = good;
  wrong[0] = 'x';
  refuses(wrong, "expected the binary glTF magic");
  wrong = good;
  wrong[4] = 1;
  refuses(wrong, "expected glTF version 2, found 1");
  refuses(good.substr(0, good.size() - 4), "expected the header's length");
  wrong = good;
  wrong[12] = '\xff';  // the JSON chunk claims more bytes than there are
  wrong[13] = '\xff';
  wrong[14] = '\xff';
  refuses(wrong, "to end within the file");
  wrong = good;
  wrong[16] = 'X';
  refuses(wrong, "expected the first chunk to be JSON");
}

TEST_CASE("writeGlb refuses a skeleton a skin cannot index and a body of too few segments", "[gltf][errors]") {
  // 65,536 joints in a chain, one frame: a skin's JOINTS_0 indices are 16 bits.
  std::vector<Joint> chain(65536);
  for (std::size_t j = 0; j < chain.size(); ++j) {
    chain[j].name = "j" + std::to_string(j);
    chain[j].parent = static_cast<int>(j) - 1;
    chain[j].offset = Eigen::Vector3d(0, 0.01, 0);
  }
  chain[0].channels = {
      {Channel::Kind::Position, Axis::X}, {Channel::Kind::Position, Axis::Y}, {Channel::Kind::Position, Axis::Z}};
  auto skeleton = std::make_shared<const Skeleton>(std::move(chain));
  const Motion big(skeleton, 1.0 / 30, std::vector<Eigen::Quaterniond>(65536, Eigen::Quaterniond::Identity()),
                   {Eigen::Vector3d::Zero()});
  REQUIRE_THROWS_WITH(writeGlb(big),
                      "glTF: expected at most 65535 joints (a skin's joint indices are 16 bits), found "
                      "65536");
  GltfWriteOptions flat;
  flat.segments = 2;
  REQUIRE_THROWS_WITH(
      writeGlb(tinyMotion(), flat),
      "glTF: expected at least 3 segments and 1 ring per capsule cap, found 2 and " + std::to_string(flat.capRings));
  // (The 2 GB limit is checked before anything grows with the motion; a motion that reaches
  // it holds twice that in quaternions, so it is not built here.)
}

}  // namespace gltf_test
