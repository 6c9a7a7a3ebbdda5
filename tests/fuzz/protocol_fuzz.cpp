// libFuzzer harness: the viewer protocol's readers (app/serve/protocol.hpp): a page's JSON
// message (parseClientMessage) and, from the same bytes, a binary pose frame (decodeFrame).
#include "fuzz_support.hpp"
#include "serve/protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The built-in controllers' names (app/builtins), which `mgrl serve` offers.
  static const std::vector<std::string> controllers = {"policy", "online_search", "random"};
  mgrl::fuzz::guarded("client message",
                      [&] { (void)mgrl::serve::parseClientMessage(mgrl::fuzz::text(data, size), controllers); });
  mgrl::fuzz::guarded("frame", [&] { (void)mgrl::serve::decodeFrame(std::span<const std::uint8_t>(data, size)); });
  return 0;
}
