// Register tables inside the hand-written guides of docs/: the marker names the
// registers, the register table gives everything the rows show, so a unit, a
// range or a default is never typed a second time.
#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "registers/exports_docs.hpp"
#include "registers/table.hpp"

namespace registers {
namespace {

using exports_detail::md_escape;

constexpr std::string_view kPrefix = "registers ";

std::string_view table_word(Table t) {
  switch (t) {
    case Table::coil: return "coil";
    case Table::discrete_input: return "discrete input";
    case Table::input_register: return "input";
    case Table::holding_register: return "holding";
  }
  return "?";
}

// The row that stands for a name: the global row, or the X row of a per-axis one.
const Register* find_row(std::string_view name) {
  for (const Register& r : all_registers())
    if (r.pattern == name && r.axis <= 0) return &r;
  return nullptr;
}

// In the row's unit (the unit column).
std::string value_text(const Register& r, std::int64_t raw) {
  if (r.type == Type::boolean) return raw ? "1" : "0";
  for (const EnumValue& v : r.values)
    if (r.type == Type::enumeration && v.value == raw) return fmt::format("{} `{}`", raw, v.name);
  return exports_detail::engineering_text(r, raw);
}

std::string address_text(const Register& r) {
  const std::string unit = r.unit == Unit::simulator ? "simulator " : "";
  const int first = r.per_axis() ? r.offset : r.address;
  const std::string at = r.words() == 2 ? fmt::format("{}-{}", first, first + 1) : fmt::format("{}", first);
  return fmt::format("{}{} {}{}", unit, table_word(r.table), r.per_axis() ? "+" : "", at);
}

std::string range_text(const Register& r) {
  if (r.type == Type::boolean) return "0/1";
  if (r.type == Type::enumeration) {
    std::string all;
    for (const EnumValue& v : r.values) all += fmt::format("{}{} `{}`", all.empty() ? "" : ", ", v.value, v.name);
    return all;
  }
  if (r.type == Type::bitmask) return "bits (see the reference)";
  // a figure the module reports over the whole width of its type: no range to tell
  if (!r.writable() && r.min == type_min(r.type) && r.max == type_max(r.type)) return "—";
  return fmt::format("{} … {}", value_text(r, r.min), value_text(r, r.max));
}

// A setting's default on every axis, folded when all six are the same; none for
// what the module only reports.
std::string default_text(const Register& first) {
  if (!first.writable()) return "—";
  bool same = true;
  std::string all;
  for (const Register& r : all_registers())
    if (r.pattern == first.pattern && r.table == first.table && r.per_axis()) {
      same = same && r.default_raw == first.default_raw;
      all += fmt::format("{}{}: {}", all.empty() ? "" : ", ", homing::kAxisUpper[static_cast<std::size_t>(r.axis)],
                         value_text(r, r.default_raw));
    }
  return !first.per_axis() || same ? value_text(first, first.default_raw) : all;
}

std::string register_table(const std::vector<const Register*>& rows) {
  const AxisKinds kinds = default_kinds();
  std::string out = fmt::format("Generated from `registers/table.cpp` by `{}`; a test fails when this table is stale.",
                                kDocsCommand);
  if (std::any_of(rows.begin(), rows.end(), [](const Register* r) { return r->per_axis(); })) {
    const AxisBlock h = axis_block(Table::holding_register);
    const AxisBlock c = axis_block(Table::coil);
    out += fmt::format(
        " Per axis: address = {} + {} × axis + offset for holding and input registers ({} + {} × axis for coils and "
        "discrete inputs), axes x y z a b c = 0..5; units as on a linear axis (a rotary one reads deg for mm).",
        h.base, h.stride, c.base, c.stride);
  }
  out += "\n\n| register | address | type | unit | range | default | description |\n|---|---|---|---|---|---|---|\n";
  for (const Register* r : rows)
    out += fmt::format("| `{}` | {} | {} | {} | {} | {} | {} |\n", r->pattern, address_text(*r), type_name(r->type),
                       r->unit_text(kinds), range_text(*r), default_text(*r), md_escape(r->description));
  return out;
}

}  // namespace

RegisterSections register_sections(std::string_view file, const std::string& document) {
  RegisterSections found;
  const std::string opening = "<!-- generated: " + std::string(kPrefix);
  std::set<std::string> seen;
  for (std::size_t at = document.find(opening); at != std::string::npos; at = document.find(opening, at + 1)) {
    if (at != 0 && document[at - 1] != '\n') continue;
    const std::size_t eol = std::min(document.find('\n', at), document.size());
    const std::string line = document.substr(at, eol - at);
    const std::size_t name_end = line.find(" (");
    const std::string name = line.substr(opening.size() - kPrefix.size(),
                                         name_end == std::string::npos ? std::string::npos
                                                                       : name_end - (opening.size() - kPrefix.size()));
    const auto fail = [&](const std::string& why) {
      return RegisterSections{{}, fmt::format("docs/{}: marker '{}': {}", file, line, why)};
    };
    if (line != begin_marker(name))
      return fail(fmt::format("the line must read exactly '{}'", begin_marker(name)));
    if (document.find(end_marker(name), eol) == std::string::npos)
      return fail(fmt::format("no line '{}' after it", end_marker(name)));
    if (!seen.insert(name).second) return fail("the same table twice in one file");
    std::vector<const Register*> rows;
    std::string_view names(name);
    names.remove_prefix(kPrefix.size());
    while (!names.empty()) {
      const std::size_t space = names.find(' ');
      const std::string_view word = names.substr(0, space);
      names.remove_prefix(space == std::string_view::npos ? names.size() : space + 1);
      if (word.empty()) continue;
      const Register* r = find_row(word);
      if (!r)
        return fail(fmt::format("no register named '{}' in registers/table.cpp (renamed? see docs/registers.md)", word));
      rows.push_back(r);
    }
    if (rows.empty()) return fail("names no register");
    found.sections.push_back({std::string(file), name, register_table(rows)});
  }
  return found;
}

SplicedDocument splice_register_sections(std::string_view file, const std::string& document) {
  RegisterSections found = register_sections(file, document);
  if (!found.error.empty()) return {std::nullopt, found.error};
  std::string text = document;
  for (const GeneratedSection& s : found.sections) {
    auto spliced = splice_section(text, s);
    if (!spliced) return {std::nullopt, fmt::format("docs/{}: cannot place the generated {}", file, s.name)};
    text = std::move(*spliced);
  }
  return {std::move(text), ""};
}

}  // namespace registers
