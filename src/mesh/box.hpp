#pragma once
/// \file Structured generator for boxes (beams, plates, blocks) with axis-aligned cracks.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"

namespace crackle::mesh {

/// An axis-aligned rectangular crack (or delamination) on a grid plane.
struct CrackSpec {
  int normal = kX;      ///< axis of the crack normal
  double at = 0.0;      ///< position of the crack plane along that axis [m]
  /// Extent of the rectangle along each axis [m]; the entry of the normal axis is ignored.
  std::array<std::array<double, 2>, 3> region{};
  double gap = 0.0;     ///< initial normal gap g0 [m] (MODEL.md eq. 9)
};

/// Geometric grading of the grid lines towards a crack front: on each side of the front, lines at
/// distance h ratio^k (k = 1..layers) from it, h the distance to the next grid line on that side.
/// The cells next to the front then shrink geometrically (hp-refinement of the crack-tip
/// singularity, which otherwise limits every order p to first-order convergence).
struct Grading {
  int layers = 0;       ///< 0: no grading; kAutoLayers: auto_layers()
  double ratio = 0.2;   ///< in (0, 1)
  /// Further positions to grade towards along each axis, besides the crack's own front [m]: a
  /// study puts the fronts of all its cases here, so that every case gets the same mesh.
  std::array<std::vector<double>, 3> fronts;
};
inline constexpr int kAutoLayers = -1;
inline constexpr int kMaxAutoLayers = 4;

/// The number of layers `mesh.box.grading: auto` gives an order-p mesh whose cells next to the front
/// are h (the largest uniform cell size of the axes graded) in a body whose thinnest side is D:
/// p - 1 + round(log2(D / h)), at least 1 and at most kMaxAutoLayers. One more layer per halving of
/// h keeps the front's share of the error shrinking faster than h; p - 1 at h = D and ratio 0.2
/// are the measurements of docs/benchmarks.md section 2 (2 layers suffice at p = 3, 3 at p = 4).
int auto_layers(int order, double cell_size, double thinnest_side);

/// A box [origin, origin + size] meshed with cells[0] x cells[1] x cells[2] elements of order p.
struct BoxSpec {
  Vec3 origin = Vec3::Zero();
  Vec3 size = Vec3::Ones();
  std::array<int, 3> cells{1, 1, 1};
  int order = 1;
  /// Grid lines added to the uniform ones along each axis [m] (those on or outside the boundary,
  /// and repeats, are ignored).
  std::array<std::vector<double>, 3> extra_lines;
  /// Grading towards the crack front (the lines of grid_lines() and build_box_mesh(box, crack)).
  Grading grading;
};

/// The positions a crack's grading is towards: each front edge (an edge of the crack rectangle
/// strictly inside the body) along its in-plane axis, and the crack plane along the normal when
/// there is a front edge at all (a crack through the whole section has no front). Per axis, ascending.
std::array<std::vector<double>, 3> crack_fronts(const BoxSpec& box, const CrackSpec& crack);

/// box.grading with automatic layers resolved for this crack (auto_layers).
Grading resolve_grading(const BoxSpec& box, const CrackSpec& crack);

/// Grid-line positions along each axis: the uniform lines of `box`, its extra lines, the lines
/// that crack edges need (a crack edge strictly inside a cell splits that cell), then box.grading's
/// layers towards every crack front (crack_fronts(), and box.grading.fronts), each graded from the
/// lines before grading, so that the result does not depend on the order of the fronts.
std::array<std::vector<double>, 3> grid_lines(const BoxSpec& box, const std::optional<CrackSpec>& crack);

/// What is wrong with a crack in a box, or an empty string if nothing is. The first word of the
/// message is the key it concerns ("plane" or "region"), for the scene loader to point at.
/// `on_uniform_plane`: the plane must also be a plane of the uniform grid (origin + k size/cells);
/// false for a crack the grid is moved to (morph_lines), which may lie anywhere inside the body.
std::string check_crack(const BoxSpec& box, const CrackSpec& crack, bool on_uniform_plane = true);

/// Grid lines made for the crack `from`, moved so that its plane and front edges land on those of
/// the crack `to` (same normal): along each axis the map is piecewise linear between knots (the
/// body's ends and `fixed[axis]`, which stay; the crack plane along the normal and the region edges
/// inside the body along the in-plane axes, which move), so every cell keeps its place in the
/// topology and stretches or shrinks with its interval. A mesh built on the result depends smoothly
/// on the crack's position and size (the forward model of `crackle identify`; a remeshed crack would
/// jump from line to line). Positions of `to` that are not strictly inside the body, or that would
/// pass a fixed line or each other, throw InputError naming `key` (the scene key of the reference).
std::array<std::vector<double>, 3> morph_lines(const BoxSpec& box, const std::array<std::vector<double>, 3>& lines,
                                               const CrackSpec& from, const CrackSpec& to,
                                               const std::array<std::vector<double>, 3>& fixed,
                                               const std::string& key = "crack.reference");

/// Meshes a box with the given grid lines (ascending, at least two per axis) and an optional crack,
/// whose plane and edges must be among the lines (the plane need not be a uniform grid plane).
/// Throws InputError if check_crack() finds a problem.
Mesh build_box_mesh(const BoxSpec& box, const std::array<std::vector<double>, 3>& lines,
                    const std::optional<CrackSpec>& crack);

/// Convenience: grid_lines() then build_box_mesh().
Mesh build_box_mesh(const BoxSpec& box, const std::optional<CrackSpec>& crack = std::nullopt);

/// Largest aspect ratio (longest over shortest edge) of the cells of a set of grid lines.
double max_aspect_ratio(const std::array<std::vector<double>, 3>& lines);

/// Largest aspect ratio of the elements of any mesh: longest over shortest extent of each element's
/// bounding box (exact for axis-aligned bricks, a rough measure for other shapes).
double max_aspect_ratio(const Mesh& mesh);

/// Names of the six box faces, in local-face order: "x-", "x+", "y-", "y+", "z-", "z+".
const std::array<std::string, 6>& box_face_names();

}  // namespace crackle::mesh
