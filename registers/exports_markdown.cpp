// registers.md: the map for people. Per-axis registers are shown once, with
// their offset in the axis block; enum values and bitmask bits are spelled out.
#include <fmt/format.h>

#include <set>

#include "registers/codec.hpp"
#include "registers/exports.hpp"

namespace registers {
namespace {

using exports_detail::engineering_text;
using exports_detail::md_escape;

std::string_view table_title(Table t) {
  switch (t) {
    case Table::coil: return "Coils (0x, FC 1/5/15)";
    case Table::discrete_input: return "Discrete inputs (1x, FC 2)";
    case Table::input_register: return "Input registers (3x, FC 4)";
    case Table::holding_register: return "Holding registers (4x, FC 3/6/16/23)";
  }
  return "?";
}

// The per-axis rows are shown once, by the X row: in the units of a linear
// axis (the sentence above each table names the rotary ones).
std::string value_cell(const Register& r, std::int64_t raw) {
  const auto unit = r.unit_text(AxisKinds{});
  if (r.type == Type::boolean) return raw ? "1" : "0";
  return unit.empty() ? engineering_text(r, raw) : fmt::format("{} {}", engineering_text(r, raw), unit);
}

// Defaults of one per-axis row on all six axes, folded when equal.
std::string axis_defaults(std::span<const Register> rows, const Register& first) {
  std::string all;
  bool same = true;
  for (const Register& r : rows)
    if (r.pattern == first.pattern && r.table == first.table && r.per_axis()) {
      if (r.default_raw != first.default_raw) same = false;
    }
  if (same) return value_cell(first, first.default_raw);
  for (const Register& r : rows)
    if (r.pattern == first.pattern && r.table == first.table && r.per_axis())
      all += fmt::format("{}{}: {}", all.empty() ? "" : ", ", homing::kAxisUpper[static_cast<std::size_t>(r.axis)],
                         r.default_raw);
  return all;
}

void write_values(std::string& out, const Register& r, std::set<const void*>& done) {
  if (r.values.empty() || !done.insert(r.values.data()).second) return;
  out += fmt::format("\n**{}** {}:\n\n", md_escape(r.pattern), r.type == Type::bitmask ? "bits" : "values");
  for (const EnumValue& v : r.values)
    out += fmt::format("- {} `{}`{}{}\n", v.value, v.name, v.meaning.empty() ? "" : ": ", md_escape(v.meaning));
  out += "\n";
}

// Which axes read deg for mm.
std::string rotary_text(const MapUnits& units) {
  if (!units.configured())
    return "on an axis whose `axis.<a>.kind` is rotary (the default of A, B, C; X, Y, Z are linear only) read deg "
           "for mm";
  std::string rotary;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if (units.kinds[a] == homing::AxisKind::rotary)
      rotary += fmt::format("{}{}", rotary.empty() ? "" : ", ", homing::kAxisUpper[a]);
  return rotary.empty() ? std::string("every axis of this machine is linear")
                        : fmt::format("on the rotary axes of this machine ({}) read deg for mm", rotary);
}

void write_table(std::string& out, std::span<const Register> rows, Unit unit, Table table, const MapUnits& units) {
  bool any = false;
  for (const Register& r : rows) any |= r.table == table;
  if (!any) return;
  const AxisBlock b = axis_block(table);
  out += fmt::format("\n### {}\n\n", table_title(table));
  const bool registers = table == Table::holding_register || table == Table::input_register;
  const std::string header = registers
      ? "| address | name | type | access | unit | scale | min | max | default | description |\n|---|---|---|---|---|---|---|---|---|---|\n"
      : "| address | name | access | default | description |\n|---|---|---|---|---|\n";
  std::set<const void*> done;

  out += "Global:\n\n" + header;
  for (const Register& r : rows) {
    if (r.table != table || r.per_axis()) continue;
    const std::string addr = r.words() == 2 ? fmt::format("{}-{}", r.address, r.address + 1) : fmt::format("{}", r.address);
    if (registers)
      out += fmt::format("| {} | `{}` | {} | {} | {} | {} | {} | {} | {} | {} |\n", addr, r.name(), type_name(r.type),
                         access_name(r.access), r.unit_text(AxisKinds{}), exports_detail::scale_text(r),
                         value_cell(r, r.min), value_cell(r, r.max), value_cell(r, r.default_raw),
                         md_escape(r.description));
    else
      out += fmt::format("| {} | `{}` | {} | {} | {} |\n", addr, r.name(), access_name(r.access), r.default_raw,
                         md_escape(r.description));
  }

  out += fmt::format("\nPer axis: address = {} + {} × axis + offset (X {}, Y {}, Z {}, A {}, B {}, C {}). "
                     "Units shown for linear axes; {}.\n\n",
                     b.base, b.stride, b.base, b.base + b.stride, b.base + 2 * b.stride, b.base + 3 * b.stride,
                     b.base + 4 * b.stride, b.base + 5 * b.stride, rotary_text(units));
  std::string axis_header = header;
  axis_header.replace(2, 7, "offset");
  out += axis_header;
  for (const Register& r : rows) {
    if (r.table != table || r.axis != 0) continue;  // the X row stands for all six
    const std::string off = r.words() == 2 ? fmt::format("+{}-{}", r.offset, r.offset + 1) : fmt::format("+{}", r.offset);
    if (registers)
      out += fmt::format("| {} | `{}` | {} | {} | {} | {} | {} | {} | {} | {} |\n", off, r.pattern, type_name(r.type),
                         access_name(r.access), r.unit_text(AxisKinds{}), exports_detail::scale_text(r),
                         value_cell(r, r.min), value_cell(r, r.max), axis_defaults(rows, r), md_escape(r.description));
    else
      out += fmt::format("| {} | `{}` | {} | {} | {} |\n", off, r.pattern, access_name(r.access), r.default_raw,
                         md_escape(r.description));
  }
  for (const Register& r : rows)
    if (r.table == table && r.axis <= 0) write_values(out, r, done);
  (void)unit;
}

}  // namespace

std::string export_markdown(const MapUnits& units) {
  std::string out = fmt::format(
      "# Modbus register map\n\n<!-- {} -->\n\n"
      "Map version {} (input register `status.map_version`). Addresses are 0-based protocol addresses (the number "
      "on the wire); many HMI packages number from 1 (holding 40001 = address 0). 32-bit values (`u32`, `i32`) take "
      "two registers, high word first unless the server runs with `--word-order low-first`, and must be written "
      "whole in one FC 16/23 request. Engineering value = raw × scale; min, max and default below are engineering "
      "values, `registers.csv` has the raw ones. Lengths are raw µm (millidegrees on a rotary axis: "
      "`axis.<a>.kind`, rotary by default on A, B, C; a gantry slave has its master's kind).\n\n"
      "Axes: x y z a b c = index 0..5; `<a>` in a name is the lowercase letter. Holding and input registers use "
      "per-axis blocks of stride 100 starting at 100; coils and discrete inputs blocks of stride 10 starting at 100. "
      "Globals sit below 100. Unmapped addresses inside a block read 0; writing one is exception 02.\n\n"
      "Writes: out of range or a setting combination that cannot work is exception 03 with nothing applied; a "
      "read-only register, an unmapped address or half of a 32-bit value is exception 02.\n",
      exports_detail::generated_note(units), kMapVersion);
  for (Unit unit : {Unit::module, Unit::simulator}) {
    out += unit == Unit::module
               ? fmt::format("\n## Module unit (unit id {} by default, `--unit`)\n", kDefaultModuleUnitId)
               : fmt::format("\n## Simulator unit (unit id {} by default, `--sim-unit`; simulator backend only)\n\n"
                             "Nothing here is persisted: the simulated machine starts from these defaults.\n",
                             kDefaultSimUnitId);
    const auto rows = registers_of(unit);
    for (Table t : {Table::holding_register, Table::input_register, Table::coil, Table::discrete_input})
      write_table(out, rows, unit, t, units);
  }
  return out;
}

}  // namespace registers
