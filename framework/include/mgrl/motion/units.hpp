#pragma once
/// \file
/// Length units of motion files and their detection from a skeleton's standing height.

#include <string_view>

namespace mgrl {

/// `cmu` is the CMU database's unit: 1/0.45 inch = 5.644 cm.
enum class LengthUnit : unsigned char { Auto, Metre, Centimetre, Inch, Cmu };

/// Parses "auto", "m", "cm", "inch" or "cmu"; throws mgrl::Error listing them otherwise
/// (the message has no prefix: callers say where the text came from).
LengthUnit parseLengthUnit(std::string_view text);
std::string_view lengthUnitName(LengthUnit unit);
/// Metres per unit (not defined for Auto).
double metresPer(LengthUnit unit);

/// The unit under which a standing height of `height` file units is most plausible for a
/// person (closest to 1.7 m by ratio). Throws mgrl::Error when none gives 0.3 to 3 m.
LengthUnit detectLengthUnit(double height, std::string_view source);

}  // namespace mgrl
