// libFuzzer harness: the .npy reader (framework/include/mgrl/core/npy.hpp), for every element type the
// bundles use.
#include "fuzz_support.hpp"
#include "mgrl/core/npy.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes = mgrl::fuzz::text(data, size);
  std::vector<std::size_t> shape;
  mgrl::fuzz::guarded("npy <f4", [&] { (void)mgrl::npyDecode<float>(bytes, "fuzz.npy", &shape); });
  mgrl::fuzz::guarded("npy <f8", [&] { (void)mgrl::npyDecode<double>(bytes, "fuzz.npy", &shape); });
  mgrl::fuzz::guarded("npy <i4", [&] { (void)mgrl::npyDecode<std::int32_t>(bytes, "fuzz.npy", &shape); });
  mgrl::fuzz::guarded("npy <u4", [&] { (void)mgrl::npyDecode<std::uint32_t>(bytes, "fuzz.npy", &shape); });
  mgrl::fuzz::guarded("npy |u1", [&] { (void)mgrl::npyDecode<std::uint8_t>(bytes, "fuzz.npy", &shape); });
  return 0;
}
