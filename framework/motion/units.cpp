#include "mgrl/motion/units.hpp"

#include <cmath>

#include <fmt/format.h>

#include "mgrl/core/enum_words.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl {

namespace {
constexpr std::array<EnumWord<LengthUnit>, 5> kLengthUnits{{{LengthUnit::Auto, "auto"},
                                                            {LengthUnit::Metre, "m"},
                                                            {LengthUnit::Centimetre, "cm"},
                                                            {LengthUnit::Inch, "inch"},
                                                            {LengthUnit::Cmu, "cmu"}}};
}  // namespace

LengthUnit parseLengthUnit(std::string_view text) { return parseWord(kLengthUnits, text); }
std::string_view lengthUnitName(LengthUnit unit) { return wordOf(kLengthUnits, unit); }

double metresPer(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Metre: return 1.0;
    case LengthUnit::Centimetre: return 0.01;
    case LengthUnit::Inch: return 0.0254;
    case LengthUnit::Cmu: return 0.0254 / 0.45;
    case LengthUnit::Auto: break;
  }
  return 1.0;
}

LengthUnit detectLengthUnit(double height, std::string_view source) {
  constexpr double kTypicalHeight = 1.7;
  LengthUnit best = LengthUnit::Metre;
  double bestScore = 1e300;
  for (LengthUnit unit : {LengthUnit::Metre, LengthUnit::Centimetre, LengthUnit::Inch, LengthUnit::Cmu}) {
    const double metres = height * metresPer(unit);
    if (!(metres > 0)) continue;
    const double score = std::abs(std::log(metres / kTypicalHeight));
    if (score < bestScore) {
      bestScore = score;
      best = unit;
    }
  }
  const double metres = height * metresPer(best);
  if (!(metres >= 0.3 && metres <= 3.0))
    throw Error(fmt::format("{}: expected a standing height that some unit makes 0.3 to 3 m, found {:.4g} file "
                            "units; pass --units m|cm|inch|cmu",
                            source, height));
  return best;
}

}  // namespace mgrl
