#pragma once
/// @file
/// Index type and sentinels shared by every HexMerge module.

#include <cstdint>
#include <limits>

namespace hexmerge {

/// Index of a vertex, tetrahedron, cell or face. 32 bits: meshes up to 4e9 entities.
using index_t = std::uint32_t;

/// "No such entity": a missing neighbour, an unassigned tet, an unused slot.
constexpr index_t NO_INDEX = std::numeric_limits<index_t>::max();
constexpr index_t NO_CELL = NO_INDEX;
constexpr index_t NO_VERTEX = NO_INDEX;

}  // namespace hexmerge
