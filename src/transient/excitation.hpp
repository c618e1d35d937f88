#pragma once
/// \file Excitations of a transient run: time signals, loads on node or face sets (the second term
/// of MODEL.md eq. 25b), and the initial fields of eq. (6).
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "mesh/mesh.hpp"

namespace crackle::transient {

enum class SignalKind {
  harmonic,  ///< \f$r(t)\sin(2\pi f (t - t_0) + \varphi)\f$, r the smooth ramp over `ramp_periods` periods
  pulse,     ///< half-sine \f$\sin(\pi (t - t_0)/\tau)\f$ for \f$t_0 \le t \le t_0 + \tau\f$, else 0
  step,      ///< 1 after a smooth ramp of length `duration` from t_0 (0: a sudden step)
};

/// A dimensionless time signal, scaled by a load's amplitude.
struct Signal {
  SignalKind kind = SignalKind::harmonic;
  double frequency = 0.0;     ///< f [Hz] (harmonic)
  double phase = 0.0;         ///< phi [rad] (harmonic)
  double ramp_periods = 3.0;  ///< harmonic: length of the ramp-in, in periods (0: none)
  double duration = 0.0;      ///< pulse: tau [s]; step: ramp length [s]
  double start = 0.0;         ///< t_0 [s]: the signal is 0 before
  double value(double time) const;
};

/// Smooth ramp from 0 to 1 over [0, length]: \f$\sin^2(\pi s / (2 L))\f$ (zero slope at both ends).
double smooth_ramp(double time, double length);

/// InputError describing the first invalid field of a signal (`where` prefixes the message).
void check_signal(const Signal& signal, const std::string& where);

/// A force of total `amplitude` [N] along `direction` times a signal, on a node set (spread evenly
/// over its DOF nodes, fem::add_point_force) or, if `faces` is not empty, on a face set as a
/// uniform traction of that total (fem::add_face_traction: consistent nodal forces).
struct ExternalLoad {
  std::string name;                  ///< for messages
  std::vector<Index> nodes;          ///< node set (used when `faces` is empty)
  std::vector<mesh::FaceRef> faces;  ///< face set
  Vec3 direction = Vec3::UnitZ();    ///< normalised on use
  double amplitude = 0.0;            ///< total force [N]
  Signal signal;
  /// When set: the load's nodal forces [N] at signal 1 over the run's DOFs, taken as they are
  /// (nodes, faces, direction and amplitude unused). A distributed run gives each rank the share of
  /// its owned DOFs of the load placed on the whole body (possibly none), so that the total force
  /// is the one-process one.
  struct NodalForces {
    std::vector<Index> dofs;
    std::vector<double> values;
  };
  std::optional<NodalForces> nodal_forces;
};

/// A field over the mesh nodes: value at node `node` (at `position`), e.g. an initial velocity.
/// The node index tells the two copies of a split crack node apart.
using NodalField = std::function<Vec3(Index node, const Vec3& position)>;

/// The field at every node as a vector over the DOFs of `dofs` (nodes sharing a DOF node: last wins).
VectorX nodal_field(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const NodalField& field);

/// A uniform value on a node set, zero elsewhere, over the DOFs of `dofs`.
VectorX uniform_on_nodes(const mesh::DofMap& dofs, const std::vector<Index>& nodes, const Vec3& value);

/// Initial state U(0), V(0) of eq. (6) over the DOFs of the run's DOF map; empty = zero.
/// Held DOFs take their prescribed displacement and zero velocity whatever is given here.
struct InitialConditions {
  VectorX displacement;
  VectorX velocity;
};

/// The mesh node closest to a point (probes given by position).
Index nearest_node(const mesh::Mesh& mesh, const Vec3& point);

}  // namespace crackle::transient
