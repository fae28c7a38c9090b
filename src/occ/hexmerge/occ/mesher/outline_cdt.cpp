#include "hexmerge/occ/mesher/outline_cdt.h"

#include <algorithm>
#include <vector>

namespace hexmerge::mesher::cgal2 {

bool mark_inside(Cdt& cdt, const std::set<std::pair<int, int>>& outline) {
  for (Cdt::Face_handle f : cdt.all_face_handles()) f->info() = -1;
  std::vector<Cdt::Face_handle> stack;
  for (Cdt::Face_handle f : cdt.all_face_handles())
    if (cdt.is_infinite(f)) f->info() = 0, stack.push_back(f);
  while (!stack.empty()) {
    const Cdt::Face_handle f = stack.back();
    stack.pop_back();
    for (int i = 0; i < 3; ++i) {
      const Cdt::Face_handle across = f->neighbor(i);
      const Cdt::Vertex_handle a = f->vertex(Cdt::cw(i)), b = f->vertex(Cdt::ccw(i));
      const bool crossing = !cdt.is_infinite(a) && !cdt.is_infinite(b) && f->is_constrained(i) &&
                            outline.count(std::minmax(a->info(), b->info()));
      const auto state = static_cast<signed char>(crossing ? 1 - f->info() : f->info());
      if (across->info() == -1) {
        across->info() = state;
        stack.push_back(across);
      } else if (across->info() != state) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace hexmerge::mesher::cgal2
