#pragma once
/// \file
/// Plugin parameters (DESIGN.md sec. 4): every plugin declares its parameters once, as a
/// list of ParamSpec (name, kind, default, range, unit, help). The same list validates a
/// YAML block strictly (unknown keys, wrong types and out-of-range values are ConfigErrors
/// `file:line:col: key.path: problem`) and documents the plugin in `mgrl list`.
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/config.hpp"

namespace mgrl {

struct ParamSpec {
  enum class Kind { Number, Integer, Choice, Boolean };
  std::string name;
  Kind kind = Kind::Number;
  double defaultValue = 0;           ///< Number, Integer (integers up to 2^53), Boolean (0/1)
  double min = 0, max = 0;           ///< Number, Integer: inclusive range
  std::string defaultChoice;         ///< Choice
  std::vector<std::string> choices;  ///< Choice: the allowed values
  /// Choice: besides `choices`, any other name is allowed (`openText` says what kind, e.g.
  /// "a skeleton role or joint"), for the plugin to check where it knows more.
  bool open = false;
  std::string openText;
  std::string unit;  ///< "m", "s", "deg", "actions", ... ("" for plain numbers)
  std::string help;

  static ParamSpec number(std::string name, double fallback, double min, double max, std::string unit,
                          std::string help);
  static ParamSpec integer(std::string name, long long fallback, long long min, long long max, std::string unit,
                           std::string help);
  static ParamSpec choice(std::string name, std::string fallback, std::vector<std::string> choices, std::string help);
  static ParamSpec boolean(std::string name, bool fallback, std::string help);
  /// A choice that also takes any other name of up to 200 printable characters (`open`).
  static ParamSpec choiceOrName(std::string name, std::string fallback, std::vector<std::string> choices,
                                std::string openText, std::string help);

  /// "0.1", "50000000", "full", "true".
  std::string defaultText() const;
  /// "number in [0, 1] m", "whole number in [1, 1000]", "one of: a, b", "true or false".
  std::string rangeText() const;
};
using ParamSpecs = std::vector<ParamSpec>;

/// Validated parameter values of one plugin instance.
class Params {
 public:
  using Value = std::variant<double, long long, std::string, bool>;

  /// Reads `node` (a map, or absent/null for all defaults) against `specs`. Keys other than
  /// the specs' names and `extraKeys` (e.g. "type", read by the caller) are errors listing
  /// the expected ones. Throws ConfigError.
  static Params read(const ConfigNode& node, const ParamSpecs& specs, const std::vector<std::string>& extraKeys);
  /// Every parameter at its default.
  static Params defaults(const ParamSpecs& specs);

  /// The value of a declared parameter; a name not declared, or of another kind, is a
  /// programming error (std::logic_error).
  double number(std::string_view name) const;
  long long integer(std::string_view name) const;
  const std::string& choice(std::string_view name) const;
  bool boolean(std::string_view name) const;
  /// The YAML block the parameters were read from (null for defaults()): plugins that
  /// read keys of their own (Registry::Entry::blockKeys) find them here.
  const ConfigNode* block() const { return node_ ? &*node_ : nullptr; }
  /// Whether the YAML gave this parameter (false for a default).
  bool given(std::string_view name) const;

  /// A ConfigError at the parameter's key (or the block, if it was defaulted), for checks
  /// that involve several parameters, e.g. `min` below `max`.
  [[noreturn]] void fail(std::string_view name, std::string_view problem) const;

  /// {"name": value, ...} for manifests and hashing (keys sorted).
  nlohmann::json toJson() const;

 private:
  struct Entry {
    ParamSpec spec;
    Value value;
    bool given = false;
  };
  const Entry& entry(std::string_view name, ParamSpec::Kind kind) const;

  std::vector<Entry> entries_;
  std::optional<ConfigNode> node_;  ///< the YAML block, if there was one
};

/// Text for `mgrl list`: one line per parameter, `name  default  unit  range  help`.
std::string describeParams(const ParamSpecs& specs, std::string_view indent);

}  // namespace mgrl
