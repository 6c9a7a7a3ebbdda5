#pragma once
// A graph header reaching up to the runtime: the include-direction check must name it.
#include "mgrl/core/error.hpp"
#include "mgrl/runtime/world.hpp"
