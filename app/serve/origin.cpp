#include "serve/origin.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <cctype>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"

namespace mgrl::serve {

namespace {

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// A header value as a log line shows it: printable, cut short.
std::string shownHeader(std::string_view text) {
  std::string out;
  for (char c : text.substr(0, 60)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  if (text.size() > 60) out += "...";
  return out;
}

bool ipLiteral(const std::string& name) {
  unsigned char buffer[16];
  if (name.size() > 2 && name.front() == '[' && name.back() == ']')
    return ::inet_pton(AF_INET6, name.substr(1, name.size() - 2).c_str(), buffer) == 1;
  return ::inet_pton(AF_INET, name.c_str(), buffer) == 1;
}

struct Parsed {
  std::string name;
  std::uint16_t port = 0;
};

// NAME[:PORT] or [IPv6][:PORT] as RFC 3986's authority without user info; nullopt if not.
std::optional<Parsed> parseAuthority(std::string_view text, std::uint16_t defaultPort) {
  const std::string s = lower(text);
  Parsed p;
  std::string_view rest;
  if (!s.empty() && s.front() == '[') {
    const std::size_t close = s.find(']');
    if (close == std::string::npos) return std::nullopt;
    p.name = s.substr(0, close + 1);
    rest = std::string_view(s).substr(close + 1);
    if (!ipLiteral(p.name)) return std::nullopt;
  } else {
    const std::size_t colon = s.find(':');
    p.name = s.substr(0, colon);
    rest = colon == std::string::npos ? std::string_view() : std::string_view(s).substr(colon);
    if (p.name.empty() || p.name.size() > 253 ||
        !std::all_of(p.name.begin(), p.name.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-'; }))
      return std::nullopt;
  }
  if (rest.empty()) {
    p.port = defaultPort;
    return p;
  }
  if (rest.front() != ':' || rest.size() < 2 || rest.size() > 6) return std::nullopt;
  unsigned value = 0;
  for (char c : rest.substr(1)) {
    if (c < '0' || c > '9') return std::nullopt;
    value = value * 10 + static_cast<unsigned>(c - '0');
  }
  if (value == 0 || value > 65535) return std::nullopt;
  p.port = static_cast<std::uint16_t>(value);
  return p;
}

struct ParsedOrigin {
  std::string scheme;
  Parsed authority;
  std::string normalised() const { return fmt::format("{}://{}:{}", scheme, authority.name, authority.port); }
};

// SCHEME://AUTHORITY with SCHEME http or https and nothing after the authority.
std::optional<ParsedOrigin> parseOrigin(std::string_view text) {
  const std::size_t sep = text.find("://");
  if (sep == std::string_view::npos) return std::nullopt;
  ParsedOrigin o;
  o.scheme = lower(text.substr(0, sep));
  if (o.scheme != "http" && o.scheme != "https") return std::nullopt;
  const auto authority = parseAuthority(text.substr(sep + 3), o.scheme == "http" ? 80 : 443);
  if (!authority) return std::nullopt;
  o.authority = *authority;
  return o;
}

}  // namespace

OriginPolicy::OriginPolicy(std::string_view listenHost, std::uint16_t port, const std::vector<std::string>& allowed)
    : port_(port) {
  const std::string host = lower(listenHost);
  wildcard_ = host == "0.0.0.0" || host == "::" || host == "[::]";
  const std::string listenName = host.find(':') != std::string::npos && host.front() != '[' ? "[" + host + "]" : host;
  for (const std::string& name : {std::string("127.0.0.1"), std::string("localhost"), std::string("[::1]"), listenName})
    if (!wildcard_ || name != listenName)
      if (std::none_of(own_.begin(), own_.end(), [&](const Authority& a) { return a.name == name; }))
        own_.push_back({name, port});
  for (const std::string& value : allowed) {
    std::string_view text = value;
    if (!text.empty() && text.back() == '/') text.remove_suffix(1);  // as a browser's address bar shows it
    const auto origin = parseOrigin(text);
    if (!origin)
      throw Error(
          fmt::format("--allow-origin {}: expected an origin such as http://mybox.lan:8080 (http or https, a "
                      "host name and an optional port, no path), found {}",
                      value, shownHeader(value)));
    extra_.push_back(origin->normalised());
    extraHosts_.push_back({origin->authority.name, origin->authority.port});
  }
}

bool OriginPolicy::ownHost(const Authority& a) const {
  if (a.port != port_) return false;
  if (wildcard_ && ipLiteral(a.name)) return true;  // an address names no one else: not a rebinding
  return std::any_of(own_.begin(), own_.end(), [&](const Authority& o) { return o.name == a.name; });
}

std::string OriginPolicy::hosts() const {
  std::vector<std::string> names;
  for (const Authority& a : own_) names.push_back(fmt::format("{}:{}", a.name, a.port));
  if (wildcard_) names.push_back(fmt::format("any address of this machine:{}", port_));
  for (const Authority& a : extraHosts_) names.push_back(a.name);
  return fmt::format("{}", fmt::join(names, ", "));
}

std::optional<std::string> OriginPolicy::refuseHost(std::string_view host) const {
  if (host.empty()) return std::string("expected a Host header naming this server, found none");
  const auto parsed = parseAuthority(host, 80);
  if (parsed) {
    if (ownHost({parsed->name, parsed->port})) return std::nullopt;
    // A proxy in front, named with --allow-origin, may forward its own name and port.
    if (std::any_of(extraHosts_.begin(), extraHosts_.end(), [&](const Authority& a) { return a.name == parsed->name; }))
      return std::nullopt;
  }
  return fmt::format("expected a Host header naming this server ({}; --allow-origin adds others), found {}", hosts(),
                     shownHeader(host));
}

std::optional<std::string> OriginPolicy::refuseOrigin(bool present, std::string_view origin) const {
  if (!present) return std::nullopt;  // not a browser: nothing a web page could make it do
  if (const auto parsed = parseOrigin(origin)) {
    if (parsed->scheme == "http" && ownHost({parsed->authority.name, parsed->authority.port})) return std::nullopt;
    if (std::find(extra_.begin(), extra_.end(), parsed->normalised()) != extra_.end()) return std::nullopt;
  }
  std::vector<std::string> origins;
  for (const Authority& a : own_) origins.push_back(fmt::format("http://{}:{}", a.name, a.port));
  for (const std::string& e : extra_) origins.push_back(e);
  return fmt::format("expected a page of this server ({}; --allow-origin adds others), found Origin {}",
                     fmt::join(origins, ", "), shownHeader(origin));
}

}  // namespace mgrl::serve
