#pragma once
/// \file
/// `mgrl compare`'s measures of a table against the reference: value iteration on
/// the behaviour's grid, or on a finer grid (--reference-set) read at the table's vertices.
#include <string>
#include <vector>

#include "mgrl/learning/discretizer.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl {

/// A greedy choice whose reference value is within this share of the best counts as
/// agreeing (ties and float round-off).
inline constexpr double kAgreementTolerance = 1e-6;

/// V(s, v) = max over s's out-actions of Q, the value the greedy policy acts on, compared
/// over every (state, vertex) pair of the table.
struct Comparison {
  double rmse = 0;            ///< root mean square of V - V_reference
  double agreement = 0;       ///< share of pairs where the table's greedy action is the reference's best
  bool interpolated = false;  ///< the reference was read at the table's vertices by interpolation
};

/// Measures `q`, whose vertices are at `positions` ((V, 3) row-major, as in a policy bundle),
/// against `reference` on `grid` (vertices at `referencePositions`). On the same grid (the
/// same vertices at the same places) vertex by vertex; on another (a finer reference, an
/// adaptive learner's refined tree) the reference's Q is interpolated multilinearly at each
/// of q's vertices (Discretizer::stencil, as the controller reads Q there; a vertex outside
/// `grid` by round-off takes the nearest point's cell).
Comparison compareTables(const QTable& q, const std::vector<double>& positions, const QTable& reference,
                         const std::vector<double>& referencePositions, const Discretizer& grid);

/// Throws mgrl::Error ("--reference-set: expected a reference grid that covers
/// behaviors.<behavior>'s grid, found its vertex ... outside ...") unless every vertex of
/// `grid` lies inside `reference` (within 1e-6 of its bounds along each non-wrapping axis).
void requireCovers(const Discretizer& reference, const Discretizer& grid, const std::string& behavior);

}  // namespace mgrl
