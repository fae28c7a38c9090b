#include "hexmerge/occ/mesher/layers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "mesher_fixtures.h"

namespace hexmerge::test {
namespace {

// The plate with a hole, refined and not swept: the layers go around the hole only (the other
// faces are lattice faces), at k layer depths (10 % jitter) into the solid.
TEST(place_layers, around_the_curved_faces_at_their_depths) {
  const double h = 2.0, thickness = 0.3 * h;
  for (int layers : {1, 2}) {
    SCOPED_TRACE(layers);
    Prepared p = prepare(occ_plate_with_hole(), h);
    repair_surface(p);
    const Placed at = place(p);
    const std::vector<Vec3>& nodes = at.nodes;
    mesher::Surroundings& around = *at.around;
    const mesher::Parity& parity = *at.parity;
    mesher::InsertedPoints inserted;
    const std::size_t placed = mesher::place_layers(nodes, p.surface, p.shape.face_solid_count,
                                                    p.lattice, -1, mesher::SweptSurface{}, layers,
                                                    thickness, 0.3 * h, parity, around, inserted);
    ASSERT_EQ(inserted.points.size(), placed);
    ASSERT_EQ(inserted.face.size(), placed);
    EXPECT_GT(placed, 50u * layers);
    std::size_t deepest = 0;
    for (std::size_t i = 0; i < placed; ++i) {
      const Vec3 q = inserted.points[i];
      EXPECT_EQ(inserted.face[i], -1);
      bool on = false;
      EXPECT_TRUE(occ_inside(p.shape, p.lattice.frame.to_world(q), on)) << i;
      // Depth from the hole's wall (r = 8, axis at (30, 20)): within a layer's 10 % jitter of
      // a whole number of layers, up to `layers`.
      const double depth = std::hypot(q.x - 30, q.y - 20) - 8;
      const double k = std::round(depth / thickness);
      EXPECT_GE(k, 1) << i;
      EXPECT_LE(k, layers) << i;
      EXPECT_NEAR(depth, k * thickness, 0.1 * k * thickness + 0.02 * h) << i;
      deepest = std::max(deepest, static_cast<std::size_t>(k));
      EXPECT_TRUE(around.layer_points.any_within(q, 1e-9));
    }
    EXPECT_EQ(deepest, static_cast<std::size_t>(layers));
  }
}

// The core laid first, then the layers (mesh_shape()'s order): the layers keep out of the core
// cells' and closing pyramids' circumspheres and `core_margin` from its points, so that the core
// laid again over the layers is the same core; laid before the core (the former order), the
// same layers cost it cells.
TEST(place_layers, keep_out_of_the_core_laid_first) {
  const double h = 2.0, thickness = 0.3 * h, margin = 0.3 * h;
  const int layers = 2;
  Prepared p = prepare(occ_plate_with_hole(), h);
  repair_surface(p);
  const std::vector<Vec3> nodes =
      mesher::frame_nodes(p.shape, p.surface, p.lattice, -1, mesher::SweptSurface{});
  const auto core_then_layers = [&](bool core_first, mesher::CoreCounts& core,
                                    mesher::InsertedPoints& inserted) {
    mesher::Surroundings around(nodes, p.surface, p.lattice, h);
    const mesher::Parity parity(nodes, p.surface, p.shape.face_solid_count, around, h);
    const auto lay = [&] {
      return mesher::place_layers(nodes, p.surface, p.shape.face_solid_count, p.lattice, -1,
                                  mesher::SweptSurface{}, layers, thickness, margin, parity, around,
                                  inserted);
    };
    std::size_t placed = core_first ? 0 : lay();
    const mesher::KeptPoints kept =
        mesher::keep_lattice_points(p.lattice, around, parity, margin, margin, true);
    core = add_core(p.lattice, around, parity, kept, -1, h, inserted);
    if (core_first) placed = lay();
    // The core laid again over the layers.
    mesher::InsertedPoints again;
    const mesher::CoreCounts second = add_core(p.lattice, around, parity, kept, -1, h, again);
    return std::make_pair(placed, second);
  };
  mesher::CoreCounts core, former_core;
  mesher::InsertedPoints inserted, former_inserted;
  const auto [placed, again] = core_then_layers(true, core, inserted);
  EXPECT_GT(core.nb_core_cells, 100u);
  EXPECT_GT(placed, 100u);
  EXPECT_EQ(again.nb_core_cells, core.nb_core_cells);
  EXPECT_EQ(again.nb_apex_points, core.nb_apex_points);
  // The layer points (after the core's) are margin from every core point.
  const std::size_t nb_core = core.nb_lattice_points + core.nb_apex_points;
  ASSERT_EQ(inserted.points.size(), nb_core + placed);
  for (std::size_t i = nb_core; i < inserted.points.size(); ++i)
    for (std::size_t j = 0; j < nb_core; ++j)
      ASSERT_GE((inserted.points[i] - inserted.points[j]).norm(), margin) << i << " " << j;
  // Layers first: the core loses cells to them.
  const auto former = core_then_layers(false, former_core, former_inserted);
  EXPECT_GT(former.first, 100u);
  EXPECT_LT(former_core.nb_core_cells, core.nb_core_cells);
}

}  // namespace
}  // namespace hexmerge::test
