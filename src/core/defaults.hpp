#pragma once
/// \file Defaults shared by the scene's parameter table (which documents them, docs/scene-format.md)
/// and the solvers' option structs, declared once here.
namespace crackle::defaults {

/// Fraction of the critical step taken by an automatic explicit time step (`transient.safety_factor`).
inline constexpr double kSafetyFactor = 0.9;
/// Lowest modes per variant (`modal.modes`).
inline constexpr int kModes = 10;
/// c of the automatic normal penalty c E/h with implicit pair springs (`crack.contact.penalty: auto`).
inline constexpr double kImplicitPenaltyFactor = 1000.0;
/// c of the automatic normal penalty with explicit pair springs.
inline constexpr double kExplicitPenaltyFactor = 1.0;

}  // namespace crackle::defaults
