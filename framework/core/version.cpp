#include "mgrl/core/version.hpp"

namespace mgrl {
const char* const kVersion = MGRL_VERSION;
}  // namespace mgrl
