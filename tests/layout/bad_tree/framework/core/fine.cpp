#include "mgrl/core/error.hpp"
// Fine: core includes core.
