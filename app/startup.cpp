#include "startup.hpp"

#include <chrono>

namespace mgrl::app {

namespace {
const std::chrono::steady_clock::time_point programStart = std::chrono::steady_clock::now();
}  // namespace

double secondsSinceStart() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - programStart).count();
}

}  // namespace mgrl::app
