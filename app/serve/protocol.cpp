#include "serve/protocol.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <initializer_list>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"

namespace mgrl::serve {

static_assert(std::endian::native == std::endian::little, "the pose frame is written as little-endian memory");

using json = nlohmann::json;

const char* modeName(Mode mode) {
  switch (mode) {
    case Mode::Target: return "target";
    case Mode::Sparring: return "sparring";
    case Mode::Crowd: return "crowd";
  }
  return "?";
}

namespace {

// A JSON value as people read it in an error message, cut short.
std::string shown(const json& value) {
  std::string text = value.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}

// The fields of one message: each is taken at most once, and whatever is left over is
// an unknown field.
class Fields {
 public:
  Fields(const json& object, std::string type) : object_(object), type_(std::move(type)) {}

  const json* optional(const char* name) {
    taken_.push_back(name);
    const auto it = object_.find(name);
    return it == object_.end() ? nullptr : &*it;
  }
  const json& required(const char* name) {
    const json* value = optional(name);
    if (!value) throw Error(fmt::format("{}: expected a field \"{}\", found none", type_, name));
    return *value;
  }
  double number(const json& value, const char* name, double lo, double hi) {
    if (!value.is_number())
      throw Error(fmt::format("{}.{}: expected a number in [{}, {}], found {}", type_, name, lo, hi, shown(value)));
    const double x = value.get<double>();
    if (!(x >= lo && x <= hi))
      throw Error(fmt::format("{}.{}: expected a number in [{}, {}], found {}", type_, name, lo, hi, shown(value)));
    return x;
  }
  int whole(const json& value, const char* name, int lo, int hi) {
    if (!value.is_number_integer() ||
        !(value.get<long long>() >= lo && value.get<long long>() <= hi))
      throw Error(fmt::format("{}.{}: expected a whole number in [{}, {}], found {}", type_, name, lo, hi,
                              shown(value)));
    return static_cast<int>(value.get<long long>());
  }
  std::string word(const json& value, const char* name, std::initializer_list<const char*> choices) {
    return word(value, name, std::vector<std::string>(choices.begin(), choices.end()));
  }
  std::string word(const json& value, const char* name, const std::vector<std::string>& choices) {
    const auto list = fmt::format("{}", fmt::join(choices, ", "));
    if (!value.is_string()) throw Error(fmt::format("{}.{}: expected one of {}, found {}", type_, name, list, shown(value)));
    std::string text = value.get<std::string>();
    if (choices.size() > 0 && std::none_of(choices.begin(), choices.end(), [&](const std::string& c) { return text == c; }))
      throw Error(fmt::format("{}.{}: expected one of {}, found {}", type_, name, list, shown(value)));
    return text;
  }
  /// Throws for a field nobody asked for.
  void finish() const {
    for (const auto& [key, value] : object_.items())
      if (std::find(taken_.begin(), taken_.end(), key) == taken_.end())
        throw Error(fmt::format("{}: unexpected field \"{}\"", type_, key.size() > 40 ? key.substr(0, 37) + "..." : key));
  }

 private:
  const json& object_;
  std::string type_;
  std::vector<std::string> taken_{"type"};
};

// {"type": "learn", "command": "start" | "step" | "run" | "stop", ...}
Learn parseLearn(Fields& fields) {
  Learn m;
  const std::string command = fields.word(fields.required("command"), "command", {"start", "step", "run", "stop"});
  if (command == "start") {
    m.command = Learn::Command::Start;
    const json& b = fields.required("behavior");
    if (!b.is_string() || b.get<std::string>().empty() || b.get<std::string>().size() > 64)
      throw Error(fmt::format("learn.behavior: expected a behaviour name, found {}", shown(b)));
    m.behavior = b.get<std::string>();
    if (const json* seed = fields.optional("seed"))
      m.seed = static_cast<std::uint64_t>(fields.whole(*seed, "seed", 0, 2'147'483'647));
    if (const json* budget = fields.optional("budget"))
      m.budget = static_cast<std::uint64_t>(fields.whole(*budget, "budget", 1, Limits::kLearnBudgetMax));
  } else if (command == "step") {
    m.command = Learn::Command::Step;
    if (const json* steps = fields.optional("steps"))
      m.steps = fields.whole(*steps, "steps", 1, Limits::kLearnStepsMax);
  } else if (command == "run") {
    m.command = Learn::Command::Run;
    m.rate = fields.number(fields.required("rate"), "rate", 0, Limits::kLearnRateMax);
  } else {
    m.command = Learn::Command::Stop;
  }
  return m;
}

// {"type": "retrain", "behavior": NAME, "set": {"reward.NAME" | "discretizer.NAME": number}}
Retrain parseRetrain(Fields& fields) {
  Retrain m;
  const json& b = fields.required("behavior");
  if (!b.is_string() || b.get<std::string>().empty() || b.get<std::string>().size() > 64)
    throw Error(fmt::format("retrain.behavior: expected a behaviour name, found {}", shown(b)));
  m.behavior = b.get<std::string>();
  const json& set = fields.required("set");
  if (!set.is_object() || set.size() > static_cast<std::size_t>(Limits::kRetrainKeysMax))
    throw Error(
        fmt::format("retrain.set: expected an object of at most {} parameters and numbers (e.g. "
                    "{{\"reward.sigma\": 0.2}}), found {}",
                    Limits::kRetrainKeysMax, shown(set)));
  for (const auto& [key, value] : set.items()) {
    // reward.NAME or discretizer.NAME, NAME in lower case and underscores.
    const std::size_t dot = key.find('.');
    const std::string section = key.substr(0, dot);
    const bool named = dot != std::string::npos && dot + 1 < key.size() && key.size() <= 64 &&
                       std::all_of(key.begin() + static_cast<std::ptrdiff_t>(dot) + 1, key.end(),
                                   [](char c) { return (c >= 'a' && c <= 'z') || c == '_' || (c >= '0' && c <= '9'); });
    if (!named || (section != "reward" && section != "discretizer"))
      throw Error(fmt::format("retrain.set: expected parameters named reward.NAME or discretizer.NAME, found \"{}\"",
                              key.size() > 40 ? key.substr(0, 37) + "..." : key));
    const std::string field = fmt::format("set[\"{}\"]", key);
    m.set[key] = fields.number(value, field.c_str(), -1e9, 1e9);
    if (value.is_number_float()) m.fractional[key] = value.dump();
  }
  return m;
}

}  // namespace

ClientMessage parseClientMessage(std::string_view text, const std::vector<std::string>& controllers) {
  if (text.size() > Limits::kMessageBytes)
    throw Error(fmt::format("message: expected at most {} bytes, found {}", Limits::kMessageBytes, text.size()));
  // The JSON reader would skip a byte order mark and stop at a NUL, ignoring what follows:
  // the message must be the JSON text and nothing else.
  if (text.starts_with("\xEF\xBB\xBF"))
    throw Error("message: expected a JSON object, found a UTF-8 byte order mark (EF BB BF) before it");
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    throw Error(fmt::format("message: expected JSON text without NUL bytes, found one at byte {}", nul));
  const json message = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (message.is_discarded()) throw Error("message: expected a JSON object, found text that is not JSON");
  if (!message.is_object()) throw Error(fmt::format("message: expected a JSON object, found {}", shown(message)));
  const auto typeIt = message.find("type");
  if (typeIt == message.end()) throw Error("message: expected a field \"type\", found none");
  if (!typeIt->is_string()) throw Error(fmt::format("message.type: expected a string, found {}", shown(*typeIt)));
  const std::string type = typeIt->get<std::string>();
  Fields fields(message, type.size() > 40 ? type.substr(0, 37) + "..." : type);

  ClientMessage result;
  if (type == "mode") {
    SetMode m;
    const std::string mode = fields.word(fields.required("mode"), "mode", {"target", "sparring", "crowd"});
    const json* avatars = fields.optional("avatars");
    if (mode == "target") {
      m = {Mode::Target, 1};
    } else if (mode == "sparring") {
      m = {Mode::Sparring, 2};
    } else {
      m = {Mode::Crowd, avatars ? fields.whole(*avatars, "avatars", Limits::kCrowdMin, Limits::kCrowdMax)
                                : Limits::kCrowdDefault};
    }
    if (avatars && mode != "crowd") throw Error(fmt::format("mode: \"avatars\" is only for the crowd, found it with {}", mode));
    result = m;
  } else if (type == "move_target") {
    const json& p = fields.required("position");
    if (!p.is_array() || p.size() != 3)
      throw Error(fmt::format("move_target.position: expected [x, y, z] in metres, found {}", shown(p)));
    MoveTarget m;
    m.position = {fields.number(p[0], "position[0]", -Limits::kTargetReach, Limits::kTargetReach),
                  fields.number(p[1], "position[1]", 0, Limits::kTargetHeightMax),
                  fields.number(p[2], "position[2]", -Limits::kTargetReach, Limits::kTargetReach)};
    result = m;
  } else if (type == "controller") {
    SetController m;
    m.controller = fields.word(fields.required("controller"), "controller", controllers);
    if (const json* h = fields.optional("horizon")) m.horizon = fields.whole(*h, "horizon", 1, Limits::kHorizonMax);
    result = m;
  } else if (type == "weights") {
    const json& w = fields.required("weights");
    if (!w.is_object() || w.empty() || w.size() > 64)
      throw Error(fmt::format("weights.weights: expected an object of behaviour names and weights, found {}", shown(w)));
    SetWeights m;
    for (const auto& [name, value] : w.items()) {
      if (name.empty() || name.size() > 64)
        throw Error(fmt::format("weights.weights: expected behaviour names of 1 to 64 characters, found \"{}\"",
                                name.substr(0, 40)));
      const std::string field = fmt::format("weights[\"{}\"]", name);
      m.weights[name] = fields.number(value, field.c_str(), 0, Limits::kWeightMax);
    }
    result = m;
  } else if (type == "pause") {
    const json& p = fields.required("paused");
    if (!p.is_boolean()) throw Error(fmt::format("pause.paused: expected true or false, found {}", shown(p)));
    result = Pause{p.get<bool>()};
  } else if (type == "step") {
    result = Step{};
  } else if (type == "speed") {
    result = SetSpeed{fields.number(fields.required("speed"), "speed", Limits::kSpeedMin, Limits::kSpeedMax)};
  } else if (type == "values") {
    const json& b = fields.required("behavior");
    if (!(b.is_null() || (b.is_string() && !b.get<std::string>().empty() && b.get<std::string>().size() <= 64)))
      throw Error(fmt::format("values.behavior: expected a behaviour name or null, found {}", shown(b)));
    result = ShowValues{b.is_null() ? std::string() : b.get<std::string>()};
  } else if (type == "learn") {
    result = parseLearn(fields);
  } else if (type == "retrain") {
    result = parseRetrain(fields);
  } else {
    throw Error(fmt::format(
        "message.type: expected one of mode, move_target, controller, weights, pause, step, speed, values, learn, "
        "retrain, found {}",
        shown(*typeIt)));
  }
  fields.finish();
  return result;
}

void FrameWriter::put(const void* bytes, std::size_t n) {
  const auto* p = static_cast<const std::uint8_t*>(bytes);
  bytes_.insert(bytes_.end(), p, p + n);
}

void FrameWriter::begin(const FrameHeader& header) {
  header_ = header;
  avatarsWritten_ = targetsWritten_ = 0;
  bytes_.clear();
  bytes_.reserve(kFrameHeaderBytes + header.avatars * avatarRecordBytes(header.joints) +
                 header.targets * kTargetRecordBytes);
  const std::uint16_t version = 1;
  put("MGRF", 4);
  put(&version, 2);
  put(&header.joints, 2);
  put(&header.avatars, 4);
  put(&header.targets, 4);
  put(&header.frame, 4);
  put(&header.time, 4);
}

void FrameWriter::avatar(std::span<const Eigen::Vector3d> joints) {
  if (joints.size() != header_.joints || avatarsWritten_ == header_.avatars || targetsWritten_ > 0)
    throw Error(fmt::format("pose frame: expected avatar {} of {} with {} joints, found {} joints", avatarsWritten_,
                            header_.avatars, header_.joints, joints.size()));
  const Eigen::Vector3f root = joints[0].cast<float>();
  put(root.data(), 12);
  std::int16_t offsets[3];
  for (const Eigen::Vector3d& joint : joints) {
    for (int k = 0; k < 3; ++k)
      offsets[k] = static_cast<std::int16_t>(std::clamp(std::lround((joint[k] - joints[0][k]) * 1000.0), -32767L, 32767L));
    put(offsets, 6);
  }
  ++avatarsWritten_;
}

void FrameWriter::target(std::uint32_t avatar, const Eigen::Vector3d& centre) {
  if (avatarsWritten_ != header_.avatars || targetsWritten_ == header_.targets)
    throw Error(fmt::format("pose frame: a target record out of place ({} of {} avatars, {} of {} targets written)",
                            avatarsWritten_, header_.avatars, targetsWritten_, header_.targets));
  const Eigen::Vector3f c = centre.cast<float>();
  put(&avatar, 4);
  put(c.data(), 12);
  ++targetsWritten_;
}

const std::vector<std::uint8_t>& FrameWriter::finish() {
  if (avatarsWritten_ != header_.avatars || targetsWritten_ != header_.targets)
    throw Error(fmt::format("pose frame: expected {} avatars and {} targets, found {} and {}", header_.avatars,
                            header_.targets, avatarsWritten_, targetsWritten_));
  return bytes_;
}

DecodedFrame decodeFrame(std::span<const std::uint8_t> bytes) {
  auto get = [&](std::size_t offset, void* out, std::size_t n) { std::memcpy(out, bytes.data() + offset, n); };
  if (bytes.size() < kFrameHeaderBytes)
    throw Error(fmt::format("pose frame: expected at least {} bytes, found {}", kFrameHeaderBytes, bytes.size()));
  if (std::memcmp(bytes.data(), "MGRF", 4) != 0) throw Error("pose frame: expected the magic MGRF");
  std::uint16_t version = 0;
  DecodedFrame frame;
  FrameHeader& h = frame.header;
  get(4, &version, 2);
  get(6, &h.joints, 2);
  get(8, &h.avatars, 4);
  get(12, &h.targets, 4);
  get(16, &h.frame, 4);
  get(20, &h.time, 4);
  if (version != 1) throw Error(fmt::format("pose frame: expected version 1, found {}", version));
  const std::size_t expected =
      kFrameHeaderBytes + std::size_t{h.avatars} * avatarRecordBytes(h.joints) + std::size_t{h.targets} * kTargetRecordBytes;
  if (bytes.size() != expected)
    throw Error(fmt::format("pose frame: expected {} bytes for {} avatars of {} joints and {} targets, found {}",
                            expected, h.avatars, h.joints, h.targets, bytes.size()));
  std::size_t at = kFrameHeaderBytes;
  for (std::uint32_t i = 0; i < h.avatars; ++i) {
    float root[3];
    get(at, root, 12);
    at += 12;
    std::vector<Eigen::Vector3d> joints(h.joints);
    for (auto& joint : joints) {
      std::int16_t o[3];
      get(at, o, 6);
      at += 6;
      for (int k = 0; k < 3; ++k) joint[k] = root[k] + o[k] / 1000.0;
    }
    frame.avatars.push_back(std::move(joints));
  }
  for (std::uint32_t i = 0; i < h.targets; ++i) {
    std::uint32_t avatar = 0;
    float c[3];
    get(at, &avatar, 4);
    get(at + 4, c, 12);
    at += kTargetRecordBytes;
    frame.targets.emplace_back(avatar, Eigen::Vector3d(c[0], c[1], c[2]));
  }
  return frame;
}

}  // namespace mgrl::serve
