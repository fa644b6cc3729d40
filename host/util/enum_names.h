// One name table per enum: the scene loader, the command line, the viewer's overlay, the benches and
// every "known: ..." list read the spelling of an enum's values from here, so the names cannot drift.
//
// An enum takes part by specializing EnumNames<E> with a `values` array of {value, name} pairs, next
// to the enum's declaration:
//   template <> struct EnumNames<Numerics> {
//     static constexpr std::array<EnumName<Numerics>, 2> values{{{Numerics::Robust, "robust"}, ...}};
//   };
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

template <typename E> struct EnumName {
  E value;
  std::string_view name;
};

template <typename E> struct EnumNames; // specialized per enum

// The value's name as written in scene files and on the command line.
template <typename E> constexpr std::string_view enumName(E value) {
  for (const auto& entry : EnumNames<E>::values) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

// The value a name stands for, or nothing for an unknown name.
template <typename E> constexpr std::optional<E> parseEnum(std::string_view name) {
  for (const auto& entry : EnumNames<E>::values) {
    if (entry.name == name) return entry.value;
  }
  return std::nullopt;
}

// Every name, in the table's order (for CLI11's IsMember and for error messages).
template <typename E> std::vector<std::string> enumNameList() {
  std::vector<std::string> names;
  for (const auto& entry : EnumNames<E>::values) names.emplace_back(entry.name);
  return names;
}

// "'a', 'b' or 'c'", as error messages list the choices.
template <typename E> std::string enumChoices() {
  std::string list;
  const auto& values = EnumNames<E>::values;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) list += i + 1 == values.size() ? " or " : ", ";
    // Appended piece by piece: "'" + std::string(...) trips GCC 12's -Wstringop-overflow (a false
    // positive in basic_string::insert at -O2).
    list += '\'';
    list += values[i].name;
    list += '\'';
  }
  return list;
}

} // namespace vkray
