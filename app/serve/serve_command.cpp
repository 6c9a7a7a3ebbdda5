#include "serve/serve_command.hpp"

#include <cstdlib>
#include <spawn.h>
#include <sys/wait.h>

#include <fmt/format.h>

#include "serve/origin.hpp"
#include "serve/server.hpp"

extern char** environ;

namespace mgrl::serve {

namespace fs = std::filesystem;

fs::path webDirectory(const fs::path& web) {
  if (!web.empty()) return web;
  if (const char* env = std::getenv("MGRL_WEB"); env && *env) return env;
  // Installed (cmake --install): PREFIX/bin/mgrl serves PREFIX/share/mgrl/web.
  std::error_code error;
  const fs::path program = fs::read_symlink("/proc/self/exe", error);
  if (!error) {
    const fs::path installed = program.parent_path().parent_path() / "share" / "mgrl" / "web";
    if (fs::is_regular_file(installed / "index.html", error)) return installed;
  }
  return MGRL_SOURCE_WEB_DIR;
}

namespace {

// Starts the desktop's browser (xdg-open) without waiting for it; says so if it cannot.
void openBrowser(const std::string& url, const WarningSink& log) {
  pid_t pid = 0;
  const char* argv[] = {"xdg-open", url.c_str(), nullptr};
  if (::posix_spawnp(&pid, "xdg-open", nullptr, nullptr, const_cast<char* const*>(argv), environ) != 0) {
    if (log) log(fmt::format("serve: --open: could not start xdg-open; open {} yourself", url));
    return;
  }
  // Reaped at once if it fails fast; a browser it starts outlives it anyway.
  int status = 0;
  ::waitpid(pid, &status, WNOHANG);
}

}  // namespace

void runServe(const ServeCommandOptions& options) {
  if (options.port < 0 || options.port > 65535)
    throw Error(fmt::format("--port: expected a port in [0, 65535] (0: any free one), found {}", options.port));
  // A malformed --allow-origin: refused before anything loads.
  [[maybe_unused]] const OriginPolicy checked(options.host, 0, options.allowOrigins);
  const fs::path web = webDirectory(options.web);
  if (options.log) options.log(fmt::format("serve: loading {} (graph and policy, once)", options.scenario.string()));
  std::shared_ptr<const ViewerAssets> assets = loadViewerAssets(options);
  ServerOptions serverOptions;
  serverOptions.host = options.host;
  serverOptions.port = static_cast<std::uint16_t>(options.port);
  serverOptions.webRoot = web;
  serverOptions.log = options.log;
  serverOptions.allowOrigins = options.allowOrigins;
  Server server(assets, serverOptions);
  if (options.host != "127.0.0.1" && options.host != "::1" && options.log)
    options.log(fmt::format("serve: warning: listening on {}, so other machines can reach this server", options.host));
  const std::string host = options.host.find(':') != std::string::npos ? "[" + options.host + "]" : options.host;
  const std::string url = fmt::format("http://{}:{}/", host, server.port());
  if (options.announce) options.announce(url);
  if (options.open) openBrowser(url, options.log);
  server.stopOnSignals();
  server.run();
  if (options.log) options.log("serve: stopped");
}

}  // namespace mgrl::serve
