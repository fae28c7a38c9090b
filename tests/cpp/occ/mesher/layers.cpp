#include "hexmerge/occ/mesher/layers.h"

#include <gtest/gtest.h>

#include <cmath>

#include "hexmerge/occ/mesher/surface_repair.h"
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
    mesher::refine(p.shape, p.surface, h, p.lattice.lattice_face, p.lattice.lattice_edge);
    mesher::collapse_short_sides(p.surface, h, p.lattice.lattice_face);
    const std::vector<Vec3> nodes =
        mesher::frame_nodes(p.shape, p.surface, p.lattice, -1, mesher::SweptSurface{});
    mesher::Surroundings around(nodes, p.surface, p.lattice, h);
    const mesher::Parity parity(nodes, p.surface, p.shape.face_solid_count, around, h);
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

}  // namespace
}  // namespace hexmerge::test
