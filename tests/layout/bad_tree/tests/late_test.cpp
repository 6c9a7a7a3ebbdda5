// A test file that opens its own namespace after a helper at file scope:
// tests/layout/test_namespaces.cmake must reject it.
#include <string>

namespace {
const std::string kBoxing = "boxing.yaml";
}  // namespace

namespace late_test {}  // namespace late_test
