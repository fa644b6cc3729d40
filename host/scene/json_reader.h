// Validated, path-aware access to a parsed JSON document. Every accessor either returns a value that
// is well-typed and in range or throws InputError naming the file, the JSON path and the problem.
#pragma once

#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "util/enum_names.h"

namespace vkray {

class JsonNode {
public:
  JsonNode(const nlohmann::json& value, std::string path, const std::string& file)
      : value_(&value), path_(std::move(path)), file_(&file) {}

  const std::string& path() const { return path_; }
  const nlohmann::json& raw() const { return *value_; }

  [[noreturn]] void fail(const std::string& problem) const;

  // Type checks.
  bool isObject() const { return value_->is_object(); }
  bool isArray() const { return value_->is_array(); }
  bool isString() const { return value_->is_string(); }
  void expectObject() const;
  void expectArray() const;

  // Objects: a required member, an optional one, and the check that no unknown key is present
  // (a typo such as "radus" is an error that suggests the nearest known key).
  JsonNode at(std::string_view key) const;
  std::optional<JsonNode> find(std::string_view key) const;
  void allowKeys(std::initializer_list<std::string_view> keys) const;
  std::vector<std::pair<std::string, JsonNode>> members() const;

  // Arrays.
  std::size_t size() const;
  JsonNode operator[](std::size_t i) const;

  // Scalars. number() rejects NaN/Inf (also as strings), numbers beyond float32's range (the GPU's),
  // and values outside [lo, hi].
  double number() const;
  double number(double lo, double hi) const;
  double positive() const; // > 0
  long long integer(long long lo, long long hi) const;
  bool boolean() const;
  std::string string() const;
  // One of the listed strings.
  std::string choice(std::initializer_list<std::string_view> options) const;
  std::string choice(const std::vector<std::string>& options) const;
  // The value of an enum named by the string, through the enum's name table (util/enum_names.h).
  template <typename E> E enumValue() const { return *parseEnum<E>(choice(enumNameList<E>())); }

  glm::dvec3 vec3() const;
  glm::dvec3 color() const; // 3 numbers >= 0, or a "#rrggbb" sRGB string
  glm::dvec3 nonZeroVec3() const;

private:
  double finiteNumber() const; // a finite double, before any range check
  std::string childPath(std::string_view key) const;
  std::string typeName() const;

  const nlohmann::json* value_;
  std::string path_;
  const std::string* file_;
};

// Parses text as JSON with // and /* */ comments; a syntax error names the line and column.
nlohmann::json parseJsonText(const std::string& text, const std::string& file);

// The candidate closest to `word` by edit distance, if it is close (fewer than 3 edits), else empty:
// the "did you mean" of unknown keys, flags and subcommands.
std::string closestMatch(std::string_view word, const std::vector<std::string>& candidates);

// Formats a double for messages without trailing noise ("-1", "0.25", "1e+30").
std::string formatNumber(double v);

} // namespace vkray
