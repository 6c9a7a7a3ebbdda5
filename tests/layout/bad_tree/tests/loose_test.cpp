// A test file whose helper sits at file scope, outside a namespace named after the file:
// tests/layout/test_namespaces.cmake must reject it.
#include <string>

namespace {
const std::string kBoxing = "boxing.yaml";
}  // namespace
