// `mgrl compare`'s measures against the reference (compare_tables.hpp).
#include "mgrl/session/compare_tables.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

// A finer reference is read where the table's own values live, so both are compared at the
// points where the table is exact by construction (its vertices).
Comparison compareTables(const QTable& q, const std::vector<double>& positions, const QTable& reference,
                         const std::vector<double>& referencePositions, const Discretizer& grid) {
  bool same = q.vertexCount() == reference.vertexCount() && positions.size() == referencePositions.size();
  for (std::size_t i = 0; same && i < positions.size(); ++i) same = std::abs(positions[i] - referencePositions[i]) < 1e-9;
  std::vector<Stencil> stencils;
  if (!same) {
    stencils.reserve(q.vertexCount());
    for (std::size_t v = 0; v < q.vertexCount(); ++v)
      stencils.push_back(grid.stencil(grid.locateClamped({positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]})));
  }
  double squares = 0;
  std::size_t agree = 0, count = 0;
  std::vector<double> interpolated;
  for (std::size_t s = 0; s < q.stateCount(); ++s) {
    const std::size_t n = q.actionsOf(s);
    if (n == 0) continue;
    interpolated.resize(n);
    for (std::size_t v = 0; v < q.vertexCount(); ++v) {
      const float* row = q.row(s, v);
      if (same) {
        const float* ref = reference.row(s, v);
        for (std::size_t j = 0; j < n; ++j) interpolated[j] = ref[j];
      } else {
        std::fill(interpolated.begin(), interpolated.end(), 0.0);
        const Stencil& st = stencils[v];
        for (int k = 0; k < st.size; ++k) {
          const float* ref = reference.row(s, st.vertex[k]);
          for (std::size_t j = 0; j < n; ++j) interpolated[j] += static_cast<double>(st.weight[k]) * ref[j];
        }
      }
      const std::size_t best = static_cast<std::size_t>(std::max_element(row, row + n) - row);
      const double refBest = *std::max_element(interpolated.begin(), interpolated.end());
      const double d = static_cast<double>(row[best]) - refBest;
      squares += d * d;
      agree += refBest - interpolated[best] <= kAgreementTolerance * std::max(1.0, std::abs(refBest));
      ++count;
    }
  }
  return Comparison{count ? std::sqrt(squares / static_cast<double>(count)) : 0.0,
                    count ? static_cast<double>(agree) / static_cast<double>(count) : 0.0, !same};
}

void requireCovers(const Discretizer& reference, const Discretizer& grid, const std::string& behavior) {
  // The measures read a table's vertices back from the bundle's positions, which do not
  // tell a speed layer, a turn layer or a velocity heading apart (turn layers come only on
  // grids with speed layers, polar_velocity's).
  if (reference.layerAxis() || grid.layerAxis())
    throw Error(fmt::format("--reference-set: behaviors.{}: a {} grid has speed layers, which a reference set cannot "
                            "be compared on yet; compare without --reference-set (against value iteration on the same grid)",
                            behavior, grid.layerAxis() ? grid.type() : reference.type()));
  for (std::size_t v = 0; v < grid.vertexCount(); ++v) {
    const std::array<double, 3> c = reference.coordinates(grid.vertexPosition(v));
    for (int i = 0; i < reference.dimension(); ++i) {
      const GridAxis& axis = reference.axes()[i];
      if (axis.wraps) continue;
      constexpr double kRoundOff = 1e-6;
      if (c[i] < axis.vertices.front() - kRoundOff || c[i] > axis.vertices.back() + kRoundOff)
        throw Error(
            fmt::format("--reference-set: expected a reference grid that covers behaviors.{}'s grid, found "
                        "its vertex {} at {} {:.4g} {}, outside the reference's {} range [{:.4g}, {:.4g}] {}",
                        behavior, v, axis.name(), c[i], axis.unit(), axis.name(), axis.vertices.front(),
                        axis.vertices.back(), axis.unit()));
    }
  }
}

}  // namespace mgrl
