#include "hexmerge/occ/mesher/solid_regions.h"

#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <algorithm>
#include <numeric>
#include <unordered_map>

namespace hexmerge::mesher {
namespace {

// A triangle by its sorted vertices, packed for hashing.
struct Key {
  index_t v[3];
  bool operator==(const Key& o) const { return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2]; }
};
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    return (static_cast<std::size_t>(k.v[0]) * 73856093u) ^
           (static_cast<std::size_t>(k.v[1]) * 19349663u) ^
           (static_cast<std::size_t>(k.v[2]) * 83492791u);
  }
};
Key key_of(index_t a, index_t b, index_t c) {
  Key k{{a, b, c}};
  std::sort(k.v, k.v + 3);
  return k;
}

index_t find(std::vector<index_t>& parent, index_t t) {
  while (parent[t] != t) t = parent[t] = parent[parent[t]];
  return t;
}

}  // namespace

std::optional<std::vector<std::int32_t>> solid_regions(
    const Shape& shape, const std::vector<index_t>& tets,
    const std::vector<std::array<index_t, 3>>& triangles, const std::vector<int>& markers) {
  const std::size_t nb_tets = tets.size() / 4;
  const int nb_solids = shape.solids.Extent();
  const int nb_faces = shape.faces.Extent();
  // Per face, the solids it bounds (by index into shape.solids).
  std::vector<std::vector<std::int32_t>> owners(static_cast<std::size_t>(nb_faces));
  for (int s = 1; s <= nb_solids; ++s) {
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(shape.solids(s), TopAbs_FACE, faces);
    for (int f = 1; f <= faces.Extent(); ++f) {
      const int i = shape.faces.FindIndex(faces(f));
      if (i > 0) owners[static_cast<std::size_t>(i - 1)].push_back(s - 1);
    }
  }
  // The face's triangles stop the flood; every other face joins its two tets.
  std::unordered_map<Key, int, KeyHash> on_face;
  on_face.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i)
    on_face.emplace(key_of(triangles[i][0], triangles[i][1], triangles[i][2]), markers[i] - 1);
  std::vector<index_t> parent(nb_tets);
  std::iota(parent.begin(), parent.end(), index_t{0});
  std::unordered_map<Key, index_t, KeyHash> open;  // a face seen once: its tet
  open.reserve(2 * nb_tets);
  // Per face triangle met, the tets on it (to intersect their solids below).
  std::vector<std::pair<index_t, int>> touching;
  for (std::size_t t = 0; t < nb_tets; ++t) {
    const index_t* v = &tets[4 * t];
    for (int f = 0; f < 4; ++f) {
      const Key k = key_of(v[(f + 1) % 4], v[(f + 2) % 4], v[(f + 3) % 4]);
      const auto face = on_face.find(k);
      if (face != on_face.end()) {
        touching.emplace_back(static_cast<index_t>(t), face->second);
        continue;
      }
      const auto [it, first] = open.emplace(k, static_cast<index_t>(t));
      if (first) continue;
      parent[find(parent, it->second)] = find(parent, static_cast<index_t>(t));
      open.erase(it);
    }
  }
  // Per component, the solids every face it touches bounds (-2: not met yet, -1: none).
  std::vector<std::int32_t> solid_of(nb_tets, -2);
  for (const auto& [t, face] : touching) {
    if (face < 0 || face >= nb_faces) return std::nullopt;
    const index_t root = find(parent, t);
    const auto& around = owners[static_cast<std::size_t>(face)];
    std::int32_t& s = solid_of[root];
    if (s == -2) {
      // The first face: one owner decides; a shared face leaves two candidates, settled below.
      s = around.size() == 1 ? around[0] : -3;
      if (s == -3 && around.size() != 2) return std::nullopt;
    } else if (around.size() == 1) {
      if (s == -3 || s == around[0]) {
        s = around[0];
      } else {
        return std::nullopt;  // faces of two different solids around one component
      }
    }
  }
  // A component touching shared faces only (a solid inside others): the solid its faces all
  // bound, found from two of them.
  std::vector<std::pair<std::int32_t, std::int32_t>> candidates(nb_tets, {-1, -1});
  for (const auto& [t, face] : touching) {
    const index_t root = find(parent, t);
    if (solid_of[root] != -3) continue;
    const auto& around = owners[static_cast<std::size_t>(face)];
    auto& [a, b] = candidates[root];
    if (a < 0) {
      a = around[0], b = around[1];
    } else {
      if (a != around[0] && a != around[1]) a = -1;
      if (b != around[0] && b != around[1]) b = -1;
      if (a < 0) std::swap(a, b);
    }
  }
  std::vector<std::int32_t> region(nb_tets);
  for (std::size_t t = 0; t < nb_tets; ++t) {
    const index_t root = find(parent, static_cast<index_t>(t));
    std::int32_t s = solid_of[root];
    if (s == -3) {
      const auto [a, b] = candidates[root];
      if (a < 0 || (b >= 0 && b != a)) return std::nullopt;  // not one solid
      s = a;
    }
    if (s < 0) return std::nullopt;  // a component on no face
    region[t] = s;
  }
  // Every face a tet touches bounds that tet's solid.
  for (const auto& [t, face] : touching) {
    const auto& around = owners[static_cast<std::size_t>(face)];
    if (std::find(around.begin(), around.end(), region[t]) == around.end()) return std::nullopt;
  }
  return region;
}

}  // namespace hexmerge::mesher
