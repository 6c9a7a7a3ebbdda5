#include "serve/static_files.hpp"

#include <algorithm>
#include <array>
#include <utility>

#include <fmt/format.h>

namespace mgrl::serve {

namespace fs = std::filesystem;

namespace {

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// True if `path` is `root` or below it, component by component.
bool within(const fs::path& root, const fs::path& path) {
  auto r = root.begin(), p = path.begin();
  for (; r != root.end(); ++r, ++p)
    if (p == path.end() || *r != *p) return false;
  return true;
}

}  // namespace

StaticLookup lookupStatic(const fs::path& root, std::string_view target) {
  auto refuse = [](int status, std::string reason) { return StaticLookup{status, {}, std::move(reason)}; };
  target = target.substr(0, target.find_first_of("?#"));
  if (target.empty() || target.front() != '/') return refuse(400, "expected a path starting with /");
  std::string decoded;
  decoded.reserve(target.size());
  for (std::size_t i = 0; i < target.size(); ++i) {
    if (target[i] != '%') {
      decoded += target[i];
      continue;
    }
    const int hi = i + 2 < target.size() ? hexDigit(target[i + 1]) : -1;
    const int lo = i + 2 < target.size() ? hexDigit(target[i + 2]) : -1;
    if (hi < 0 || lo < 0) return refuse(400, "expected %XX escapes of two hexadecimal digits");
    decoded += static_cast<char>(hi * 16 + lo);
    i += 2;
  }
  if (decoded.find('\0') != std::string::npos || decoded.find('\\') != std::string::npos)
    return refuse(400, "expected a path without NUL or backslash");
  fs::path relative;
  std::size_t begin = 1;
  while (begin <= decoded.size()) {
    const std::size_t end = std::min(decoded.find('/', begin), decoded.size());
    const std::string_view segment = std::string_view(decoded).substr(begin, end - begin);
    if (segment == "." || segment == "..") return refuse(400, "expected a path without . or .. segments");
    // Dotfiles (.package-lock.json, .git, an editor's swap file) are no part of the page.
    if (!segment.empty() && segment.front() == '.')
      return refuse(404, "no such file (names that start with a dot are not served)");
    if (!segment.empty()) relative /= fs::path(std::string(segment));
    begin = end + 1;
  }
  if (decoded.back() == '/') relative /= "index.html";
  std::error_code ec;
  const fs::path file = fs::weakly_canonical(root / relative, ec);
  if (ec || !within(root, file)) return refuse(400, "expected a path inside the web folder");
  if (!fs::is_regular_file(file, ec)) return refuse(404, "no such file");
  return {200, file, {}};
}

std::string_view mimeType(const fs::path& file) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 11> kTypes{{
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".map", "application/json"},
      {".png", "image/png"},
      {".svg", "image/svg+xml"},
      {".ico", "image/x-icon"},
      {".wasm", "application/wasm"},
      {".txt", "text/plain; charset=utf-8"},
  }};
  const std::string extension = file.extension().string();
  for (const auto& [ext, type] : kTypes)
    if (ext == extension) return type;
  return "application/octet-stream";
}

}  // namespace mgrl::serve
