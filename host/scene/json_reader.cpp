// Validated JSON access with JSON paths in every message (see json_reader.h).
#include "scene/json_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "util/error.h"

namespace vkray {

namespace {

// Levenshtein distance, for "did you mean" suggestions on unknown keys.
std::size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

double srgbToLinear(double c) {
  return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

// Length of the well-formed UTF-8 sequence at s[i] (RFC 3629: no overlong forms, no surrogates,
// nothing past U+10FFFF), or 0 if the bytes there are not one.
std::size_t utf8Length(const std::string& s, std::size_t i) {
  auto at = [&](std::size_t k) { return i + k < s.size() ? static_cast<unsigned char>(s[i + k]) : 0u; };
  unsigned b0 = at(0);
  std::size_t n = b0 >= 0xc2 && b0 <= 0xdf ? 2 : b0 >= 0xe0 && b0 <= 0xef ? 3 : b0 >= 0xf0 && b0 <= 0xf4 ? 4 : 0;
  if (n == 0) return 0;
  // The second byte's range depends on the first (Unicode Table 3-7).
  unsigned lo = b0 == 0xe0 ? 0xa0 : b0 == 0xf0 ? 0x90 : 0x80;
  unsigned hi = b0 == 0xed ? 0x9f : b0 == 0xf4 ? 0x8f : 0xbf;
  if (at(1) < lo || at(1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k) {
    if (at(k) < 0x80 || at(k) > 0xbf) return 0;
  }
  return n;
}

// Messages are one line of text: control characters that a key, a name or a file name brings in,
// and bytes that are not UTF-8, are written as escapes ("\n", "\x1b", "\xe9").
std::string printable(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    char c = s[i];
    auto u = static_cast<unsigned char>(c);
    if (u >= 0x80) {
      if (std::size_t n = utf8Length(s, i)) {
        out.append(s, i, n);
        i += n - 1;
      } else {
        char hex[8];
        std::snprintf(hex, sizeof hex, "\\x%02x", u);
        out += hex;
      }
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (u < 0x20 || u == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    } else {
      out += c;
    }
  }
  return out;
}

// Deeper nesting than this is refused while parsing. A scene is a few levels deep (a polygon's
// vertex is at 4); the cap keeps nlohmann's recursive operations (copy, merge_patch for "base",
// destruction) far from the stack's end and stops a hostile file before it is built.
constexpr int kMaxJsonDepth = 64;

// Where the nesting first goes deeper than kMaxJsonDepth: the byte offset (text.size() if it never
// does), skipping strings and comments.
// Steps over JSON that is not code: a string (tracked through inString across calls) or a comment
// starting at i, leaving i on its last character. True when text[i] is code.
bool atCode(const std::string& text, std::size_t& i, bool& inString) {
  char c = text[i];
  if (inString) {
    if (c == '\\')
      ++i;
    else if (c == '"')
      inString = false;
    return false;
  }
  if (c == '"') {
    inString = true;
    return false;
  }
  if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
    i = std::min(text.find('\n', i), text.size());
    return false;
  }
  if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
    auto end = text.find("*/", i + 2);
    i = end == std::string::npos ? text.size() : end + 1;
    return false;
  }
  return true;
}

std::size_t tooDeepAt(const std::string& text) {
  int depth = 0;
  bool inString = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (!atCode(text, i, inString)) continue;
    if (text[i] == '[' || text[i] == '{') {
      if (++depth > kMaxJsonDepth) return i;
    } else if (text[i] == ']' || text[i] == '}') {
      --depth;
    }
  }
  return text.size();
}

std::string lineAndColumn(const std::string& text, std::size_t byte) {
  std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + byte, '\n'));
  std::size_t lineStart = byte == 0 ? std::string::npos : text.rfind('\n', byte - 1);
  std::size_t column = byte - (lineStart == std::string::npos ? 0 : lineStart + 1) + 1;
  return std::to_string(line) + ":" + std::to_string(column);
}

// Where `token` first stands alone (not inside a string, a comment or a longer token), or text.size().
std::size_t findToken(const std::string& text, const std::string& token) {
  auto partOfNumber = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+';
  };
  bool inString = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (!atCode(text, i, inString)) continue;
    if (text.compare(i, token.size(), token) == 0 && (i == 0 || !partOfNumber(text[i - 1])) &&
        (i + token.size() >= text.size() || !partOfNumber(text[i + token.size()]))) {
      return i;
    }
  }
  return text.size();
}

} // namespace

std::string closestMatch(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t bestDistance = 3; // suggest only close matches
  for (const auto& candidate : candidates) {
    std::size_t d = editDistance(word, candidate);
    if (d < bestDistance) {
      bestDistance = d;
      best = candidate;
    }
  }
  return best;
}

std::string formatNumber(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

nlohmann::json parseJsonText(const std::string& text, const std::string& file) {
  // Nesting is checked by a scan before parsing, not by a parser callback: nlohmann's callback
  // parser looks through the whole enclosing array at the end of every object (3.11), which makes
  // an array of n objects cost O(n^2) (ten million "{}" took hours).
  if (std::size_t deep = tooDeepAt(text); deep < text.size()) {
    throw InputError(printable(file) + ":" + lineAndColumn(text, deep),
                     "invalid JSON: nested more than " + std::to_string(kMaxJsonDepth) + " levels deep");
  }
  try {
    return nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is 1-based and points just past the offending character.
    std::size_t byte = e.byte > 0 ? std::min<std::size_t>(e.byte - 1, text.size()) : 0;
    std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + byte, '\n'));
    std::size_t lineStart = text.rfind('\n', byte == 0 ? 0 : byte - 1);
    std::size_t column = byte - (lineStart == std::string::npos ? 0 : lineStart + 1) + 1;
    if (byte > 0 && lineStart == byte - 1) column = 1;
    std::string what = e.what();
    // nlohmann's text is "[json.exception.parse_error.101] parse error at line 1, column 2: ...".
    auto colon = what.find(": ", what.find("parse error"));
    std::string detail = colon == std::string::npos ? what : what.substr(colon + 2);
    throw InputError(printable(file) + ":" + std::to_string(line) + ":" + std::to_string(column),
                     "invalid JSON: " + printable(detail));
  } catch (const nlohmann::json::exception& e) {
    // e.g. "number overflow parsing '1e400'": a number no double can hold.
    // nlohmann gives no position for it: the number is looked up in the text, where it stands as a
    // whole token outside strings and comments.
    std::string what = e.what();
    auto close = what.find("] ");
    std::string where = printable(file);
    auto open = what.find('\'');
    auto end = open == std::string::npos ? open : what.find('\'', open + 1);
    if (end != std::string::npos) {
      std::string token = what.substr(open + 1, end - open - 1);
      if (std::size_t at = findToken(text, token); at < text.size()) where += ":" + lineAndColumn(text, at);
    }
    throw InputError(where, "invalid JSON: " + printable(close == std::string::npos ? what : what.substr(close + 2)));
  }
}

void JsonNode::fail(const std::string& problem) const {
  throw InputError(printable(*file_ + ": " + (path_.empty() ? "(top level)" : path_)), printable(problem));
}

std::string JsonNode::typeName() const {
  switch (value_->type()) {
  case nlohmann::json::value_t::null:
    return "null";
  case nlohmann::json::value_t::object:
    return "an object";
  case nlohmann::json::value_t::array:
    return "an array";
  case nlohmann::json::value_t::string:
    return "a string";
  case nlohmann::json::value_t::boolean:
    return "a boolean";
  case nlohmann::json::value_t::number_integer:
  case nlohmann::json::value_t::number_unsigned:
  case nlohmann::json::value_t::number_float:
    return "a number";
  default:
    return "binary data";
  }
}

std::string JsonNode::childPath(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

void JsonNode::expectObject() const {
  if (!value_->is_object()) fail("must be an object, got " + typeName());
}

void JsonNode::expectArray() const {
  if (!value_->is_array()) fail("must be an array, got " + typeName());
}

JsonNode JsonNode::at(std::string_view key) const {
  expectObject();
  auto it = value_->find(key);
  if (it == value_->end()) fail("missing required key '" + std::string(key) + "'");
  return JsonNode(*it, childPath(key), *file_);
}

std::optional<JsonNode> JsonNode::find(std::string_view key) const {
  expectObject();
  auto it = value_->find(key);
  if (it == value_->end()) return std::nullopt;
  return JsonNode(*it, childPath(key), *file_);
}

void JsonNode::allowKeys(std::initializer_list<std::string_view> keys) const {
  expectObject();
  for (auto it = value_->begin(); it != value_->end(); ++it) {
    const std::string& k = it.key();
    if (std::find(keys.begin(), keys.end(), k) != keys.end()) continue;
    std::string best = closestMatch(k, std::vector<std::string>(keys.begin(), keys.end()));
    std::string msg = "unknown key '" + k + "'";
    if (!best.empty()) msg += " (did you mean '" + best + "'?)";
    fail(msg);
  }
}

std::vector<std::pair<std::string, JsonNode>> JsonNode::members() const {
  expectObject();
  std::vector<std::pair<std::string, JsonNode>> out;
  for (auto it = value_->begin(); it != value_->end(); ++it) {
    out.emplace_back(it.key(), JsonNode(it.value(), childPath(it.key()), *file_));
  }
  return out;
}

std::size_t JsonNode::size() const {
  expectArray();
  return value_->size();
}

JsonNode JsonNode::operator[](std::size_t i) const {
  expectArray();
  return JsonNode((*value_)[i], path_ + "[" + std::to_string(i) + "]", *file_);
}

double JsonNode::finiteNumber() const {
  if (value_->is_string()) {
    // JSON has no NaN/Inf literals; people write them as strings. Name the problem precisely.
    std::string s = value_->get<std::string>();
    std::string lower;
    for (char c : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower.find("nan") != std::string::npos) fail("must be a finite number, got NaN");
    if (lower.find("inf") != std::string::npos) fail("must be a finite number, got " + s);
  }
  if (!value_->is_number()) fail("must be a number, got " + typeName());
  double v = value_->get<double>();
  if (!std::isfinite(v)) fail("must be a finite number, got " + formatNumber(v));
  return v;
}

double JsonNode::number() const {
  double v = finiteNumber();
  // The kernel computes in float32: a larger number would reach it as infinity.
  if (std::abs(v) > static_cast<double>(std::numeric_limits<float>::max())) {
    fail("must be within float32's range (+-3.40282347e+38; the GPU computes in float32), got " + formatNumber(v));
  }
  return v;
}

double JsonNode::number(double lo, double hi) const {
  double v = finiteNumber();
  if (v < lo || v > hi) {
    fail("must be in [" + formatNumber(lo) + ", " + formatNumber(hi) + "], got " + formatNumber(v));
  }
  return v;
}

double JsonNode::positive() const {
  double v = number();
  if (!(v > 0.0)) fail("must be > 0, got " + formatNumber(v));
  return v;
}

long long JsonNode::integer(long long lo, long long hi) const {
  double v = finiteNumber();
  if (v != std::floor(v)) fail("must be a whole number, got " + formatNumber(v));
  if (v < static_cast<double>(lo) || v > static_cast<double>(hi)) {
    fail("must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + formatNumber(v));
  }
  return static_cast<long long>(v);
}

bool JsonNode::boolean() const {
  if (!value_->is_boolean()) fail("must be true or false, got " + typeName());
  return value_->get<bool>();
}

std::string JsonNode::string() const {
  if (!value_->is_string()) fail("must be a string, got " + typeName());
  return value_->get<std::string>();
}

std::string JsonNode::choice(std::initializer_list<std::string_view> options) const {
  return choice(std::vector<std::string>(options.begin(), options.end()));
}

std::string JsonNode::choice(const std::vector<std::string>& options) const {
  std::string s = string();
  if (std::find(options.begin(), options.end(), s) != options.end()) return s;
  std::string list;
  for (const auto& o : options) list += (list.empty() ? "'" : ", '") + o + "'";
  fail("must be one of " + list + ", got '" + s + "'");
}

glm::dvec3 JsonNode::vec3() const {
  if (!value_->is_array()) fail("must be an array of 3 numbers, got " + typeName());
  if (value_->size() != 3) {
    fail("must be an array of 3 numbers, got " + std::to_string(value_->size()) + " elements");
  }
  return {(*this)[0].number(), (*this)[1].number(), (*this)[2].number()};
}

glm::dvec3 JsonNode::color() const {
  if (value_->is_string()) {
    std::string s = value_->get<std::string>();
    if (s.size() == 7 && s[0] == '#' && s.find_first_not_of("0123456789abcdefABCDEF", 1) == std::string::npos) {
      glm::dvec3 c;
      for (int i = 0; i < 3; ++i) c[i] = srgbToLinear(std::stoi(s.substr(1 + 2 * i, 2), nullptr, 16) / 255.0);
      return c;
    }
    fail("must be [r, g, b] (linear, >= 0) or \"#rrggbb\", got \"" + s + "\"");
  }
  glm::dvec3 c = vec3();
  for (int i = 0; i < 3; ++i) {
    if (c[i] < 0.0)
      (*this)[static_cast<std::size_t>(i)].fail("colour components must be >= 0, got " + formatNumber(c[i]));
  }
  return c;
}

glm::dvec3 JsonNode::nonZeroVec3() const {
  glm::dvec3 v = vec3();
  if (v == glm::dvec3(0.0)) fail("must not be the zero vector");
  return v;
}

} // namespace vkray
