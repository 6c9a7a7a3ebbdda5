#include "cli_support.hpp"

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include <catch2/catch.hpp>

namespace mgrl::test {

std::string shellWord(const std::filesystem::path& p) {
  std::string word(1, '\'');
  word += p.string();
  word += '\'';
  return word;
}

std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> result;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) result.push_back(l);
  return result;
}

std::string Run::lastErrorLine() const {
  const std::vector<std::string> all = lines(err);
  return all.empty() ? std::string() : all.back();
}

nlohmann::json Run::report() const {
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  nlohmann::json parsed;
  REQUIRE_NOTHROW(parsed = nlohmann::json::parse(out));  // the whole of stdout, nothing before or after
  REQUIRE(parsed.is_object());
  return parsed;
}

Run runMgrl(const std::string& arguments, const std::filesystem::path& streams, const std::string& prefix) {
  const std::filesystem::path out = streams / "stdout.txt", err = streams / "stderr.txt";
  const std::string command = prefix + " " + shellWord(MGRL_BINARY) + " " + arguments + " >" + shellWord(out) +
                              " 2>" + shellWord(err) + " </dev/null";
  const int raw = std::system(command.c_str());
  Run r;
  r.status = raw != -1 && WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = readText(out);
  r.err = readText(err);
  return r;
}

}  // namespace mgrl::test
