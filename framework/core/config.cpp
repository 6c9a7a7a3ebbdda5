#include "mgrl/core/config.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/files.hpp"

namespace mgrl {

ConfigNode::ConfigNode(YAML::Node node, std::shared_ptr<Origin> origin, std::string path, YAML::Mark parentMark)
    : node_(std::move(node)), origin_(std::move(origin)), path_(std::move(path)), mark_(parentMark) {
  // A node without a position of its own (e.g. an absent child) reports its parent's.
  if (node_ && node_.Mark().line >= 0) mark_ = node_.Mark();
}

ConfigNode ConfigNode::parse(std::string_view text, std::string source) {
  auto origin = std::make_shared<Origin>(Origin{std::move(source), {}});
  try {
    YAML::Node root = YAML::Load(std::string(text));
    return ConfigNode(root, origin, "", YAML::Mark());
  } catch (const YAML::Exception& e) {
    throw ConfigError(fmt::format("{}:{}:{}: expected valid YAML, found a syntax error: {}", origin->source, e.mark.line + 1,
                                  e.mark.column + 1, e.msg));
  }
}

ConfigNode ConfigNode::parseFile(const std::filesystem::path& path) { return parse(readFile(path), path.string()); }

std::string ConfigNode::where() const {
  // A value set on the command line is not at the file's line (which may hold another).
  for (auto it = origin_->overrides.rbegin(); it != origin_->overrides.rend(); ++it) {
    const std::string& path = it->first;
    if (path_ == path || (path_.size() > path.size() && path_.compare(0, path.size(), path) == 0 &&
                          (path_[path.size()] == '.' || path_[path.size()] == '[')))
      return it->second;
  }
  if (mark_.line < 0) return origin_->source;
  return fmt::format("{}:{}:{}", origin_->source, mark_.line + 1, mark_.column + 1);
}

void ConfigNode::noteOverride(const std::string& path, std::string flag) const {
  origin_->overrides.emplace_back(path, std::move(flag));
}

void ConfigNode::fail(std::string_view problem) const {
  if (path_.empty()) throw ConfigError(fmt::format("{}: {}", where(), problem));
  throw ConfigError(fmt::format("{}: {}: {}", where(), path_, problem));
}

std::string ConfigNode::childPath(std::string_view key) const {
  return path_.empty() ? std::string(key) : fmt::format("{}.{}", path_, key);
}

namespace {

std::string describe(const YAML::Node& node) {
  if (!node || node.IsNull()) return "nothing";
  if (node.IsMap()) return "a map";
  if (node.IsSequence()) return "a list";
  return quoteToken(node.Scalar());
}

}  // namespace

bool ConfigNode::has(std::string_view key) const {
  if (!node_.IsMap()) return false;
  for (const auto& item : node_)
    if (item.first.IsScalar() && item.first.Scalar() == key) return true;
  return false;
}

ConfigNode ConfigNode::child(std::string_view key) const {
  if (!node_.IsMap()) fail(fmt::format("expected a map with key '{}', found {}", key, describe(node_)));
  for (const auto& item : node_)
    if (item.first.IsScalar() && item.first.Scalar() == key) return ConfigNode(item.second, origin_, childPath(key), item.first.Mark());
  return ConfigNode(YAML::Node(), origin_, childPath(key), mark_);
}

ConfigNode ConfigNode::section(std::string_view key) const {
  if (!has(key)) fail(fmt::format("expected a '{}' section, found none", key));
  ConfigNode result = child(key);
  if (!result.isMap()) result.fail(fmt::format("expected a map, found {}", describe(result.node_)));
  return result;
}

std::vector<std::string> ConfigNode::keys() const {
  if (!node_.IsMap()) fail(fmt::format("expected a map, found {}", describe(node_)));
  std::vector<std::string> result;
  for (const auto& item : node_) {
    if (!item.first.IsScalar())
      ConfigNode(item.first, origin_, path_, mark_).fail("expected a plain key, found a map or list as key");
    if (std::find(result.begin(), result.end(), item.first.Scalar()) != result.end())
      ConfigNode(item.second, origin_, childPath(item.first.Scalar()), item.first.Mark())
          .fail("expected each key once, found it again (a second copy would be ignored)");
    result.push_back(item.first.Scalar());
  }
  return result;
}

std::vector<ConfigNode> ConfigNode::elements() const {
  if (!node_.IsSequence()) fail(fmt::format("expected a list, found {}", describe(node_)));
  std::vector<ConfigNode> result;
  std::size_t i = 0;
  for (const auto& item : node_) result.push_back(ConfigNode(item, origin_, fmt::format("{}[{}]", path_, i++), mark_));
  return result;
}

void ConfigNode::allowOnly(std::initializer_list<std::string_view> allowed) const {
  if (isNull()) return;
  if (!node_.IsMap()) fail(fmt::format("expected a map, found {}", describe(node_)));
  keys();  // rejects a key given twice
  for (const auto& item : node_) {
    const std::string key = item.first.IsScalar() ? item.first.Scalar() : std::string("?");
    bool known = false;
    for (std::string_view a : allowed) known = known || a == key;
    if (!known)
      ConfigNode(item.second, origin_, childPath(key), item.first.Mark())
          .fail(fmt::format("unknown key (expected one of: {})", fmt::join(allowed, ", ")));
  }
}

double ConfigNode::asNumber(double min, double max) const {
  double value = 0;
  if (!node_.IsScalar() || !YAML::convert<double>::decode(node_, value) || !std::isfinite(value))
    fail(fmt::format("expected a number in [{}, {}], found {}", min, max, describe(node_)));
  if (value < min || value > max) fail(fmt::format("expected a number in [{}, {}], found {}", min, max, value));
  return value;
}

long long ConfigNode::asInteger(long long min, long long max) const {
  long long value = 0;
  if (!node_.IsScalar() || !YAML::convert<long long>::decode(node_, value)) {
    // Budgets read better as 5e7: accept a number written with an exponent if it is whole.
    double number = 0;
    if (!node_.IsScalar() || !YAML::convert<double>::decode(node_, number) || !std::isfinite(number) ||
        number != std::floor(number) || std::fabs(number) > 9.007199254740992e15)
      fail(fmt::format("expected a whole number in [{}, {}], found {}", min, max, describe(node_)));
    value = static_cast<long long>(number);
  }
  if (value < min || value > max) fail(fmt::format("expected a whole number in [{}, {}], found {}", min, max, value));
  return value;
}

bool ConfigNode::asBool() const {
  bool value = false;
  if (!node_.IsScalar() || !YAML::convert<bool>::decode(node_, value))
    fail(fmt::format("expected true or false, found {}", describe(node_)));
  return value;
}

std::string ConfigNode::asString() const {
  if (!node_.IsScalar()) fail(fmt::format("expected a string, found {}", describe(node_)));
  return node_.Scalar();
}

double ConfigNode::number(std::string_view key, double fallback, double min, double max) const {
  return has(key) ? child(key).asNumber(min, max) : fallback;
}
long long ConfigNode::integer(std::string_view key, long long fallback, long long min, long long max) const {
  return has(key) ? child(key).asInteger(min, max) : fallback;
}
bool ConfigNode::boolean(std::string_view key, bool fallback) const {
  return has(key) ? child(key).asBool() : fallback;
}
std::string ConfigNode::string(std::string_view key, std::string fallback) const {
  return has(key) ? child(key).asString() : fallback;
}

}  // namespace mgrl
