#include "mgrl/core/params.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace mgrl {

ParamSpec ParamSpec::number(std::string name, double fallback, double min, double max, std::string unit,
                            std::string help) {
  ParamSpec p;
  p.name = std::move(name);
  p.kind = Kind::Number;
  p.defaultValue = fallback;
  p.min = min;
  p.max = max;
  p.unit = std::move(unit);
  p.help = std::move(help);
  return p;
}

ParamSpec ParamSpec::integer(std::string name, long long fallback, long long min, long long max, std::string unit,
                             std::string help) {
  ParamSpec p = number(std::move(name), static_cast<double>(fallback), static_cast<double>(min),
                       static_cast<double>(max), std::move(unit), std::move(help));
  p.kind = Kind::Integer;
  return p;
}

ParamSpec ParamSpec::choice(std::string name, std::string fallback, std::vector<std::string> choices,
                            std::string help) {
  ParamSpec p;
  p.name = std::move(name);
  p.kind = Kind::Choice;
  p.defaultChoice = std::move(fallback);
  p.choices = std::move(choices);
  p.help = std::move(help);
  return p;
}

ParamSpec ParamSpec::choiceOrName(std::string name, std::string fallback, std::vector<std::string> choices,
                                  std::string openText, std::string help) {
  ParamSpec p = choice(std::move(name), std::move(fallback), std::move(choices), std::move(help));
  p.open = true;
  p.openText = std::move(openText);
  return p;
}

ParamSpec ParamSpec::boolean(std::string name, bool fallback, std::string help) {
  ParamSpec p;
  p.name = std::move(name);
  p.kind = Kind::Boolean;
  p.defaultValue = fallback ? 1 : 0;
  p.help = std::move(help);
  return p;
}

std::string ParamSpec::defaultText() const {
  switch (kind) {
    case Kind::Number: return fmt::format("{}", defaultValue);
    case Kind::Integer: return fmt::format("{}", static_cast<long long>(defaultValue));
    case Kind::Choice: return defaultChoice;
    case Kind::Boolean: return defaultValue != 0 ? "true" : "false";
  }
  return {};
}

std::string ParamSpec::rangeText() const {
  const std::string suffix = unit.empty() ? "" : " " + unit;
  switch (kind) {
    case Kind::Number: return fmt::format("number in [{}, {}]{}", min, max, suffix);
    case Kind::Integer:
      return fmt::format("whole number in [{}, {}]{}", static_cast<long long>(min), static_cast<long long>(max),
                         suffix);
    case Kind::Choice:
      return open ? fmt::format("one of: {}, or {}", fmt::join(choices, ", "), openText)
                  : fmt::format("one of: {}", fmt::join(choices, ", "));
    case Kind::Boolean: return "true or false";
  }
  return {};
}

Params Params::defaults(const ParamSpecs& specs) {
  Params params;
  for (const ParamSpec& spec : specs) {
    Entry e{spec, {}, false};
    switch (spec.kind) {
      case ParamSpec::Kind::Number: e.value = spec.defaultValue; break;
      case ParamSpec::Kind::Integer: e.value = static_cast<long long>(spec.defaultValue); break;
      case ParamSpec::Kind::Choice: e.value = spec.defaultChoice; break;
      case ParamSpec::Kind::Boolean: e.value = spec.defaultValue != 0; break;
    }
    params.entries_.push_back(std::move(e));
  }
  return params;
}

Params Params::read(const ConfigNode& node, const ParamSpecs& specs, const std::vector<std::string>& extraKeys) {
  Params params = defaults(specs);
  if (node.isNull()) return params;
  params.node_ = node;
  std::vector<std::string> allowed = extraKeys;
  for (const ParamSpec& spec : specs) allowed.push_back(spec.name);
  for (const std::string& key : node.keys()) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
      node.child(key).fail(specs.empty() ? fmt::format("unknown key (this plugin takes no parameters; expected only: {})",
                                                       fmt::join(allowed, ", "))
                                         : fmt::format("unknown key (expected one of: {})", fmt::join(allowed, ", ")));
  }
  for (Entry& e : params.entries_) {
    if (!node.has(e.spec.name)) continue;
    const ConfigNode value = node.child(e.spec.name);
    e.given = true;
    switch (e.spec.kind) {
      case ParamSpec::Kind::Number: e.value = value.asNumber(e.spec.min, e.spec.max); break;
      case ParamSpec::Kind::Integer:
        e.value = value.asInteger(static_cast<long long>(e.spec.min), static_cast<long long>(e.spec.max));
        break;
      case ParamSpec::Kind::Boolean: e.value = value.asBool(); break;
      case ParamSpec::Kind::Choice: {
        const std::string text = value.asString();
        const bool printable = !text.empty() && text.size() <= 200 &&
                               std::all_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) > ' ' && c != 0x7f; });
        if (e.spec.open && !printable)
          value.fail(fmt::format("expected one of: {}, or {} (up to 200 printable characters, no spaces), found {}",
                                 fmt::join(e.spec.choices, ", "), e.spec.openText, quoteToken(text)));
        if (!e.spec.open && std::find(e.spec.choices.begin(), e.spec.choices.end(), text) == e.spec.choices.end())
          value.fail(fmt::format("expected one of: {}, found {}", fmt::join(e.spec.choices, ", "), quoteToken(text)));
        e.value = text;
        break;
      }
    }
  }
  return params;
}

const Params::Entry& Params::entry(std::string_view name, ParamSpec::Kind kind) const {
  for (const Entry& e : entries_)
    if (e.spec.name == name) {
      if (e.spec.kind != kind) throw std::logic_error(fmt::format("parameter '{}' read as another kind", name));
      return e;
    }
  throw std::logic_error(fmt::format("parameter '{}' was not declared", name));
}

double Params::number(std::string_view name) const { return std::get<double>(entry(name, ParamSpec::Kind::Number).value); }
long long Params::integer(std::string_view name) const {
  return std::get<long long>(entry(name, ParamSpec::Kind::Integer).value);
}
const std::string& Params::choice(std::string_view name) const {
  return std::get<std::string>(entry(name, ParamSpec::Kind::Choice).value);
}
bool Params::boolean(std::string_view name) const { return std::get<bool>(entry(name, ParamSpec::Kind::Boolean).value); }

bool Params::given(std::string_view name) const {
  for (const Entry& e : entries_)
    if (e.spec.name == name) return e.given;
  throw std::logic_error(fmt::format("parameter '{}' was not declared", name));
}

void Params::fail(std::string_view name, std::string_view problem) const {
  if (node_) {
    if (node_->has(name)) node_->child(name).fail(problem);
    node_->fail(fmt::format("{}: {}", name, problem));
  }
  throw ConfigError(fmt::format("{}: {}", name, problem));
}

nlohmann::json Params::toJson() const {
  nlohmann::json result = nlohmann::json::object();
  for (const Entry& e : entries_) std::visit([&](const auto& v) { result[e.spec.name] = v; }, e.value);
  return result;
}

std::string describeParams(const ParamSpecs& specs, std::string_view indent) {
  if (specs.empty()) return fmt::format("{}(no parameters)\n", indent);
  std::size_t width = 0, defaultWidth = 0;
  for (const ParamSpec& spec : specs) {
    width = std::max(width, spec.name.size());
    defaultWidth = std::max(defaultWidth, spec.defaultText().size());
  }
  std::string text;
  for (const ParamSpec& spec : specs)
    text += fmt::format("{}{:<{}}  default {:<{}}  {}: {}\n", indent, spec.name, width, spec.defaultText(),
                        defaultWidth, spec.rangeText(), spec.help);
  return text;
}

}  // namespace mgrl
