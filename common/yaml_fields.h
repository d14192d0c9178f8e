#pragma once

// Typed values out of a YAML file's nodes (yaml-cpp), every refusal one line "SOURCE:LINE:
// problem" thrown as std::invalid_argument: the manifests' and the watch's camera files' one
// reader of fields.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/csv.h"

namespace clogscope {

// The YAML document `text` read from `source`; a syntax error is "SOURCE:LINE: problem".
inline YAML::Node LoadYamlText(const std::string& text, const std::string& source) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(fmt::format("{}:{}: {}", source, e.mark.line + 1, e.msg));
  }
}

class YamlFields {
 public:
  explicit YamlFields(std::string source) : source_(std::move(source)) {}

  const std::string& source() const { return source_; }
  [[noreturn]] void Fail(const YAML::Node& n, const std::string& problem) const {
    throw std::invalid_argument(fmt::format("{}:{}: {}", source_, n.Mark().line + 1, problem));
  }
  // Every key of `map` one of `known`: "unknown key 'K' (known: A, B, …)".
  void CheckKeys(const YAML::Node& map, const std::set<std::string>& known) const {
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    CheckKeys(
        map, [&](const std::string& key) { return known.count(key) > 0; }, "", "known: " + list);
  }
  // Every key of `map` plain, `known` and given once ("unknown key 'K' WHERE (HINT)"; yaml-cpp
  // keeps a repeated key, and which one a reader took would depend on how it looked).
  void CheckKeys(const YAML::Node& map, const std::function<bool(const std::string&)>& known,
                 const std::string& where, const std::string& hint) const {
    std::map<std::string, int> seen;  // key -> its line
    for (const auto& kv : map) {
      if (!kv.first.IsScalar()) Fail(kv.first, "a key must be a plain name");
      const std::string key = kv.first.Scalar();
      if (!known(key))
        Fail(kv.first,
             fmt::format("unknown key '{}'{}{} ({})", key, where.empty() ? "" : " ", where, hint));
      const auto [it, first] = seen.emplace(key, kv.first.Mark().line + 1);
      if (!first)
        Fail(kv.first, fmt::format("'{}' given twice (also at line {})", key, it->second));
    }
  }
  std::string Text(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) Fail(n, key + ": expected a single value");
    return n.Scalar();
  }
  double Number(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) Fail(n, key + ": expected a number");
    try {
      return ParseNumberField(n.Scalar(), source_, key);  // the one number parser of files
    } catch (const std::invalid_argument&) {
      Fail(n, fmt::format("{}: '{}' is not a number", key, n.Scalar()));
    }
  }
  int Whole(const YAML::Node& n, const std::string& key) const {
    const double v = Number(n, key);
    if (v != std::floor(v) || std::abs(v) > 1e9)
      Fail(n, fmt::format("{}: expected a whole number", key));
    return static_cast<int>(v);
  }
  bool Flag(const YAML::Node& n, const std::string& key) const {
    const std::string text = Text(n, key);
    if (text == "true") return true;
    if (text == "false") return false;
    Fail(n, fmt::format("{}: '{}': expected true or false", key, text));
  }
  std::vector<std::string> TextList(const YAML::Node& n, const std::string& key) const {
    if (n.IsScalar()) return {n.Scalar()};
    if (!n.IsSequence()) Fail(n, key + ": expected a value or a list");
    std::vector<std::string> out;
    for (const auto& item : n) out.push_back(Text(item, key));
    return out;
  }

 private:
  std::string source_;
};

}  // namespace clogscope
