#include "featherdrive/constraint/row_kinds.hpp"

#include <array>
#include <stdexcept>

namespace featherdrive {
namespace {

constexpr std::array<RowKindInfo, RowKinds::size> make_table() {
  std::array<RowKindInfo, RowKinds::size> table{};
  RowKinds::for_each([&]<class E>(E, int field, int) {
    using K = typename E::Kind;
    table[E::index] = {K::name,  K::force, std::span<const RowField>(K::fields),
                       E::index, field,    &K::check,
                       &K::active};
  });
  return table;
}

const std::array<RowKindInfo, RowKinds::size> kTable = make_table();

}  // namespace

std::span<const RowKindInfo> row_kinds() { return kTable; }

std::string row_kind_names() {
  std::string names;
  for (const RowKindInfo& k : kTable) names += (names.empty() ? "" : ", ") + std::string(k.name);
  return names;
}

const RowKindInfo& row_kind(std::string_view name) {
  for (const RowKindInfo& k : kTable)
    if (k.name == name) return k;
  throw std::invalid_argument("unknown row kind '" + std::string(name) + "' (row kinds: " +
                              row_kind_names() + ")");
}

int row_field_column(const RowKindInfo& kind, std::string_view field) {
  std::string known;
  for (size_t j = 0; j < kind.fields.size(); ++j) {
    if (kind.fields[j].name == field) return kind.offset + static_cast<int>(j);
    known += (j ? ", " : "") + std::string(kind.fields[j].name);
  }
  throw std::invalid_argument(std::string(kind.name) + " has no field '" + std::string(field) +
                              "' (its fields: " + known + ")");
}

}  // namespace featherdrive
