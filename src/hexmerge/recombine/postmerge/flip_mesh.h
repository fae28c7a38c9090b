#pragma once
/// @file
/// A tet mesh that can be changed by flips (2-3, 3-2, 4-4) and edge contractions, with an undo
/// journal: the post-merge stage's working copy of the tets (postmerge.h).
///
/// Tets are never changed in place: a change kills its old tets and appends new ones, so a tet
/// id names the same four vertices for as long as it is alive. Every change replaces a set of
/// tets by another tiling of the same union (same boundary triangles), all of one region, every
/// new tet positively oriented with a scaled Jacobian of at least the given floor; a change that
/// cannot satisfy that changes nothing. Flips keep every node; a contraction leaves one inner
/// node unused. Node moves (smooth(), and flips and contractions made valid by one with
/// set_smoothing) move a node whose tets are all of one region and unlocked and have no face on
/// the domain boundary at it, or (set_slide_on_faces) whose boundary faces lie in one plane,
/// within that plane; every tet at it stays positive, so the star's union (its boundary
/// triangles re-tiling the same flat polygon) and every region's volume are kept. A vertex split
/// (split()) adds one node past the existing ones and re-tiles an inner node's star.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hexmerge/core/index.h"
#include "hexmerge/mesh/tet_mesh.h"

namespace hexmerge {

/// Counts of the flips done (and not undone).
struct FlipCounts {
  std::size_t flips_23 = 0;  ///< two tets sharing a face -> three around a new edge
  std::size_t flips_32 = 0;  ///< three tets around an edge -> two sharing a face
  std::size_t flips_44 = 0;  ///< four tets around an edge -> four around another edge
  /// Half-edge contractions: an inner node merged into a neighbour, its tets around the edge
  /// gone (contract()).
  std::size_t contractions = 0;
  /// Inner nodes moved (smooth(), or to make a flip or contraction valid); a node moved twice
  /// counts twice.
  std::size_t moves = 0;
  /// Vertex splits: an inner node split into an edge, one node added (split()).
  std::size_t splits = 0;
};

class FlipMesh {
 public:
  /// Copies the tets, regions and points of `mesh`.
  explicit FlipMesh(const TetMesh& mesh);

  /// When on, a flip or contraction refused because a new tet would be inverted or below its
  /// floor is tried again after moving one vertex of every such tet (smooth()): the move and the
  /// change are made together or not at all.
  void set_smoothing(bool on) { smoothing_ = on; }
  /// When on, a node inside a flat face of the domain (its boundary triangles in one plane, its
  /// tets of one region) may move too, in that plane (movable(), smooth()).
  void set_slide_on_faces(bool on) { slide_on_faces_ = on; }
  /// A further condition on every position smooth() takes node v to (called with the node
  /// there and the tets the caller replaces next): e.g. that the elements the stage may still
  /// take at v stay acceptable.
  using MoveGuard = std::function<bool(index_t v, const std::vector<index_t>& leaving)>;
  void set_move_guard(MoveGuard guard) { guard_ = std::move(guard); }

  index_t nb_slots() const { return static_cast<index_t>(alive_.size()); }
  bool alive(index_t t) const { return alive_[t] != 0; }
  const index_t* tet(index_t t) const { return &tets_[4 * static_cast<std::size_t>(t)]; }
  std::int32_t region(index_t t) const { return regions_[t]; }
  const double* point(index_t v) const { return &points_[3 * static_cast<std::size_t>(v)]; }

  /// Locked tets are never flipped (the tets of elements the stage keeps).
  bool locked(index_t t) const { return locked_[t] != 0; }
  void set_locked(index_t t, bool value) { locked_[t] = value ? 1 : 0; }

  /// The alive tets holding both vertices (appended to `out`, which is cleared first).
  void tets_with_edge(index_t a, index_t b, std::vector<index_t>& out) const;
  /// The alive tet holding the three vertices other than `except`, or NO_CELL.
  index_t tet_with_face(index_t a, index_t b, index_t c, index_t except) const;
  /// The vertex of alive tet t that is none of a, b, c.
  index_t opposite(index_t t, index_t a, index_t b, index_t c) const;

  /// 2-3 flip of the face shared by tets t0 and t1: three tets around the edge joining their
  /// opposite vertices. False (nothing changed) when they do not share a face, a tet is locked
  /// or dead, their regions differ, or a new tet would fall below `min_quality`.
  bool flip_23(index_t t0, index_t t1, double min_quality);
  /// Removes interior edge (u, v) when exactly 3 tets (3-2 flip) or 4 tets (4-4 flip, `diagonal`
  /// 0 or 1 picks the new edge between ring vertices 0-2 or 1-3) surround it. Same conditions as
  /// flip_23.
  bool remove_edge(index_t u, index_t v, int diagonal, double min_quality);
  /// Half-edge contraction of edge (from, onto): node `from` leaves the mesh, the tets holding
  /// both nodes are gone and in every other tet of `from` it is replaced by `onto`. Only when
  /// the tets of `from` are all of one region and unlocked, `from` is inside the domain or its
  /// boundary faces lie in one plane with `onto` on them (a node inside a flat face of the
  /// geometry), and every tet made is positive with a scaled Jacobian of at least `min_quality`:
  /// the tets made tile the same union, so the boundary surface and every region's volume are
  /// kept and no other node moves. False (nothing changed) otherwise.
  bool contract(index_t from, index_t onto, double min_quality);
  /// The paper's vertex split (section 4.3.2): node v becomes an edge v-n, n a new node (id
  /// nb_nodes() before the call). The tets of v in `to_new` (some, not all) take n instead of v,
  /// the others keep v, and each face at v between the two sets gets a tet holding both v and n
  /// (the ring of tets around the new edge); v goes to `at_v` and n to `at_new`. Only when v is
  /// an inner node (no face on the domain boundary at it) whose tets are all of one region and
  /// unlocked, and every tet made (v's moved ones too) is positive with a scaled Jacobian of at
  /// least `min_quality`: the star's surface is kept, so the tets made tile its union (the
  /// winding number argument) and every region's volume is kept. Returns n, or NO_VERTEX
  /// (nothing changed).
  index_t split(index_t v, const std::vector<index_t>& to_new, const std::array<double, 3>& at_v,
                const std::array<double, 3>& at_new, double min_quality);
  /// Nodes, added ones included (ids 0 to nb_nodes() - 1).
  index_t nb_nodes() const { return static_cast<index_t>(points_.size() / 3); }

  /// A measure of a cell at node v that a move must bring to at least `need` (e.g. the scaled
  /// Jacobian of a pyramid on v), evaluated with the node where it is being tried.
  struct Goal {
    std::function<double()> quality;
    double need;
  };
  /// Moves node v (movable(); in its face's plane when it is on the boundary) so that every goal is
  /// met and each of its tets other than `leaving` (tets the caller replaces next, in the same undo
  /// step) stays positive with a scaled Jacobian of at least min(min_quality, its scaled Jacobian
  /// before). With `leaving` empty the star keeps its union (its surface is fixed and every tet
  /// stays positive), so every region's volume is kept. The position is found by a pattern search
  /// from the node's place and from its neighbours' centroid (steps of a third of the mean edge
  /// length at v, halved down to kSmallestStep of it), maximising the least margin over the goals
  /// and tets. False (nothing changed) when no position meets them all (and the move guard). Work:
  /// the tets at v, times the positions tried (at most kMaxTrials).
  bool smooth(index_t v, const std::vector<Goal>& goals, const std::vector<index_t>& leaving,
              double min_quality);
  /// v is an inner node (or, with set_slide_on_faces, a node inside a flat face of the domain)
  /// whose tets are all of one region and unlocked (smooth() may move it).
  bool movable(index_t v) const;

  /// The undo journal: undo(mark()) restores the mesh as it was at the mark, counts included.
  std::size_t mark() const { return journal_.size(); }
  void undo(std::size_t mark);

  const FlipCounts& counts() const { return counts_; }

  /// The alive tets as a compact tet mesh on the points as moved (tets in slot order).
  TetMesh compact() const;

 private:
  /// The journal's kind of a contraction (flips are 23, 32, 44), of a node move, of a split's
  /// tets and of its added node (and its other node's place before).
  static constexpr std::uint8_t kContraction = 1;
  static constexpr std::uint8_t kMove = 2;
  static constexpr std::uint8_t kSplit = 3;
  static constexpr std::uint8_t kSplitNode = 4;
  /// Positions smooth() tries at most for one node, and its smallest step, a share of the mean
  /// edge length at the node (1/1000 on box-delaunay-100k: 59,008 cells against 59,001, for
  /// twice the time of the moves).
  static constexpr int kMaxTrials = 400;
  static constexpr double kSmallestStep = 1e-2;
  /// Boundary faces are one plane when every corner is within this fraction of their longest
  /// edge from the first face's plane.
  static constexpr double kFlatTolerance = 1e-12;
  /// The boundary faces at a node lie in one plane, and `onto` is a corner of one of them.
  bool flat_boundary(const std::vector<std::array<index_t, 3>>& faces, index_t onto) const;
  /// The faces lie in one plane (within kFlatTolerance of their longest edge); its unit normal.
  bool plane_of(const std::vector<std::array<index_t, 3>>& faces, std::array<double, 3>& n) const;
  bool replace(const std::vector<index_t>& old_tets,
               const std::vector<std::array<index_t, 4>>& new_tets, double min_quality,
               std::uint8_t kind);
  /// replace(), and when it is refused and smoothing is on, replace() again after moving a node
  /// that every refused new tet holds (smooth() with those tets as goals).
  bool change(const std::vector<index_t>& old_tets,
              const std::vector<std::array<index_t, 4>>& new_tets, double min_quality,
              std::uint8_t kind);
  /// The alive tets holding v.
  void star(index_t v, std::vector<index_t>& out) const;
  /// Face f (the one opposite corner f) of tet t has no tet on its other side.
  bool boundary_face(index_t t, int f) const;

  std::vector<double> points_;
  bool smoothing_ = false;
  MoveGuard guard_;
  /// Node moves made, for undo: the node and where it was.
  struct Move {
    index_t node;
    std::array<double, 3> from;
  };
  std::vector<Move> moves_;
  /// Splits made, for undo: the node split and where it was (the added node is the last).
  std::vector<Move> split_nodes_;
  bool with_regions_;
  std::vector<index_t> tets_;
  std::vector<std::int32_t> regions_;
  std::vector<char> alive_;
  std::vector<char> locked_;
  /// Tets that held each vertex at some time (dead and stale ids included; filtered on use).
  std::vector<std::vector<index_t>> incidence_;
  /// The input's tets' neighbours (TetTopology's, 4 per tet): an input tet keeps its slot, so
  /// across a face of one that is alive is its neighbour there when that one is alive too, or
  /// nothing on the domain's boundary (tet_with_face() without a scan).
  std::vector<index_t> input_neighbors_;
  struct Entry {
    index_t tet;
    bool created;  ///< created (undo kills it) or killed (undo revives it)
    /// 0: none, else the change counted (23, 32, 44, kContraction, kSplit) on its last entry;
    /// kMove: a node move (`tet` is its index in moves_); kSplitNode: a split's added node
    /// (`tet` is its index in split_nodes_)
    std::uint8_t kind;
  };
  std::vector<Entry> journal_;
  /// Per node, found on first use by movable().
  static constexpr std::uint8_t kUnknown = 0, kInner = 1, kOnFlatFace = 2, kFixed = 3;
  mutable std::vector<std::uint8_t> kind_;
  /// The unit normal of the flat face a kOnFlatFace node lies in.
  mutable std::unordered_map<index_t, std::array<double, 3>> face_normal_;
  bool slide_on_faces_ = false;
  FlipCounts counts_;
};

}  // namespace hexmerge
