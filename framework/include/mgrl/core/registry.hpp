#pragma once
/// \file
/// One registry per seam (DESIGN.md sec. 4): a snake_case name maps to a factory and the
/// parameters it reads. The application registers every plugin explicitly (app/plugins.cpp);
/// nothing registers itself behind the reader's back.
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "mgrl/core/config.hpp"
#include "mgrl/core/params.hpp"

namespace mgrl {

template <class Product, class... Context>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Product>(const Params&, Context...)>;
  struct Entry {
    std::string name;
    std::string summary;  ///< one line for `mgrl list`
    ParamSpecs params;
    Factory make;
    /// Keys of the block besides `type` and the parameters that a plugin reads itself
    /// (e.g. a reward's list of `terms`), with the function that checks them and returns
    /// their normalised JSON (defaults filled in) for manifests and keys. The factory
    /// reaches them through Params::block().
    std::vector<std::string> blockKeys = {};
    std::function<nlohmann::json(const ConfigNode& block)> readBlock = nullptr;
    /// A block that builds a working instance, for the seam's conformance suite
    /// (tests/conformance_test.cpp); "" means `{type: NAME}` with the defaults.
    std::string example = {};
    /// Parameters that default to a related block's values instead of their specs' (a
    /// success condition's: those of the behaviour's reward term of its kind).
    std::vector<std::string> inherited = {};
  };

  /// `seam` names the kind of plugin in messages: "discretizer", "reward", ...
  explicit Registry(std::string seam) : seam_(std::move(seam)) {}

  const std::string& seam() const { return seam_; }

  /// Adds a plugin; a second plugin of the same name is a programming error.
  void add(Entry entry) {
    if (find(entry.name)) throw std::logic_error(fmt::format("{} '{}' registered twice", seam_, entry.name));
    entries_.push_back(std::move(entry));
  }

  const Entry* find(std::string_view name) const {
    for (const Entry& e : entries_)
      if (e.name == name) return &e;
    return nullptr;
  }

  /// Builds the plugin a YAML block names: `{type: NAME, ...parameters}`. A missing or
  /// unknown type is a ConfigError listing the known names; parameters are read strictly.
  std::unique_ptr<Product> create(const ConfigNode& block, Context... context) const {
    const Params params = check(block);
    const Entry& entry = entryFor(block);
    return block.withLocation([&] { return entry.make(params, context...); });
  }

  /// The plugin a block names; ConfigError for a missing or unknown type.
  const Entry& entryFor(const ConfigNode& block) const {
    if (!block.isMap()) block.fail(fmt::format("expected a map with 'type: <{}>', found {}", seam_, describeKnown()));
    if (!block.has("type")) block.fail(fmt::format("expected a 'type' key naming the {} ({})", seam_, describeKnown()));
    const ConfigNode typeNode = block.child("type");
    const std::string type = typeNode.asString();
    const Entry* entry = find(type);
    if (!entry) typeNode.fail(fmt::format("unknown {} {} (known: {})", seam_, quoteToken(type), describeKnown()));
    return *entry;
  }

  /// Checks a block's type and parameters without building the plugin (checks that need
  /// the plugin's context, e.g. the graph, happen in create()).
  Params check(const ConfigNode& block) const {
    const Entry& entry = entryFor(block);
    std::vector<std::string> extra{"type"};
    extra.insert(extra.end(), entry.blockKeys.begin(), entry.blockKeys.end());
    Params params = Params::read(block, entry.params, extra);
    if (entry.readBlock) entry.readBlock(block);
    return params;
  }

  /// The block's parameters as JSON, defaults filled in, with the normalised extra keys
  /// (Entry::readBlock); {"type": type} alone for an unknown type. A null block: the
  /// defaults of `fallbackType`.
  nlohmann::json blockJson(const ConfigNode& block, const std::string& fallbackType) const {
    const std::string type = block.isNull() ? fallbackType : block.child("type").asString();
    nlohmann::json out = nlohmann::json::object();
    out["type"] = type;
    const Entry* entry = find(type);
    if (!entry) return out;
    const Params params = block.isNull() ? Params::defaults(entry->params) : check(block);
    // Named, not iterated as temporaries: items() would outlive them (C++20 extends only
    // the range's own lifetime).
    const nlohmann::json values = params.toJson();
    for (const auto& item : values.items()) out[item.key()] = item.value();
    if (entry->readBlock && !block.isNull()) {
      const nlohmann::json extra = entry->readBlock(block);
      for (const auto& item : extra.items()) out[item.key()] = item.value();
    }
    return out;
  }

  const std::vector<Entry>& entries() const { return entries_; }

  /// The registered names, in registration order.
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const Entry& e : entries_) out.push_back(e.name);
    return out;
  }

  /// "a, b, c", or "none registered".
  std::string describeKnown() const {
    return entries_.empty() ? std::string("none registered") : fmt::format("{}", fmt::join(names(), ", "));
  }

 private:
  std::string seam_;
  std::vector<Entry> entries_;
};

}  // namespace mgrl
