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

/// A box [origin, origin + size] meshed with cells[0] x cells[1] x cells[2] elements of order p.
struct BoxSpec {
  Vec3 origin = Vec3::Zero();
  Vec3 size = Vec3::Ones();
  std::array<int, 3> cells{1, 1, 1};
  int order = 1;
  /// Grid lines added to the uniform ones along each axis [m] (those on or outside the boundary,
  /// and repeats, are ignored).
  std::array<std::vector<double>, 3> extra_lines;
};

/// Grid-line positions along each axis: the uniform lines of `box`, its extra lines, and the lines
/// that crack edges need (a crack edge strictly inside a cell splits that cell).
std::array<std::vector<double>, 3> grid_lines(const BoxSpec& box, const std::optional<CrackSpec>& crack);

/// What is wrong with a crack in a box, or an empty string if nothing is. The first word of the
/// message is the key it concerns ("plane" or "region"), for the scene loader to point at.
std::string check_crack(const BoxSpec& box, const CrackSpec& crack);

/// Meshes a box with the given grid lines (ascending, at least two per axis) and an optional crack.
/// Throws InputError if check_crack() finds a problem.
Mesh build_box_mesh(const BoxSpec& box, const std::array<std::vector<double>, 3>& lines,
                    const std::optional<CrackSpec>& crack);

/// Convenience: grid_lines() then build_box_mesh().
Mesh build_box_mesh(const BoxSpec& box, const std::optional<CrackSpec>& crack = std::nullopt);

/// Names of the six box faces, in local-face order: "x-", "x+", "y-", "y+", "z-", "z+".
const std::array<std::string, 6>& box_face_names();

}  // namespace crackle::mesh
