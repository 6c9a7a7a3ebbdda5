#pragma once
/// \file
/// Reading YAML configuration (scenarios, plugin parameters) strictly: every value is
/// checked for type and range, unknown keys are errors, and every message says where:
/// `boxing.yaml:14:3: graph.treshold: unknown key (expected one of ...)`.
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

/// A configuration mistake: `what()` is `source:line:col: key.path: problem`.
class ConfigError : public Error {
 public:
  using Error::Error;
};

/// A node of a YAML document with its key path and source name, for messages.
class ConfigNode {
 public:
  /// Parses YAML text. Throws ConfigError `source:line:col: problem` for malformed YAML.
  static ConfigNode parse(std::string_view text, std::string source);
  /// Reads and parses a file; throws mgrl::Error if it cannot be read.
  static ConfigNode parseFile(const std::filesystem::path& path);

  /// Dotted key path of this node ("" for the document root).
  const std::string& path() const { return path_; }
  const std::string& source() const { return origin_->source; }
  const YAML::Node& yaml() const { return node_; }
  bool isMap() const { return node_.IsMap(); }
  bool isNull() const { return !node_ || node_.IsNull(); }

  bool has(std::string_view key) const;
  /// The child `key` (which must exist: see has()); throws ConfigError if this is not a map.
  ConfigNode child(std::string_view key) const;
  /// A required child map; throws ConfigError naming the missing section.
  ConfigNode section(std::string_view key) const;
  /// Keys of a map in document order; throws ConfigError if this is not a map.
  std::vector<std::string> keys() const;
  /// Elements of a sequence; throws ConfigError if this is not one.
  std::vector<ConfigNode> elements() const;

  /// Throws ConfigError at the first key not in `allowed`, listing the allowed ones.
  void allowOnly(std::initializer_list<std::string_view> allowed) const;

  /// Scalars of this node, checked: a number in [min, max], an integer in [min, max], a
  /// boolean, a string. Throws ConfigError saying what was expected and found.
  double asNumber(double min, double max) const;
  long long asInteger(long long min, long long max) const;
  bool asBool() const;
  std::string asString() const;

  /// The same for an optional child, `fallback` when it is absent.
  double number(std::string_view key, double fallback, double min, double max) const;
  long long integer(std::string_view key, long long fallback, long long min, long long max) const;
  bool boolean(std::string_view key, bool fallback) const;
  std::string string(std::string_view key, std::string fallback) const;

  /// Returns `check()`; an mgrl::Error it throws without a place (e.g. from a parser of
  /// enumeration names or a validate()) is rethrown as a ConfigError at this node.
  template <class F>
  decltype(auto) withLocation(F&& check) const {
    try {
      return check();
    } catch (const ConfigError&) {
      throw;
    } catch (const Error& e) {
      fail(e.what());
    }
  }

  /// Records that the value at dotted `path` came from the command line flag `flag`
  /// (e.g. `--set world.mode=target`): a mistake there, or below it, is then reported as
  /// `--set world.mode=target: world.mode: problem`, not at the file's line. Applies to
  /// every node of this document.
  void noteOverride(const std::string& path, std::string flag) const;

  /// Throws ConfigError `source:line:col: path: problem` at this node.
  [[noreturn]] void fail(std::string_view problem) const;
  /// "source:line:col" of this node.
  std::string where() const;

 private:
  struct Origin {
    std::string source;
    std::vector<std::pair<std::string, std::string>> overrides;  ///< (dotted path, flag)
  };
  ConfigNode(YAML::Node node, std::shared_ptr<Origin> origin, std::string path, YAML::Mark parentMark);
  std::string childPath(std::string_view key) const;

  YAML::Node node_;
  std::shared_ptr<Origin> origin_;
  std::string path_;
  YAML::Mark mark_;
};

}  // namespace mgrl
