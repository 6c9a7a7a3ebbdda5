// Bundle directories (graph cache, policy bundles, checkpoints)
// under kills and concurrent writers. A replaced bundle is never missing, two writers of
// one bundle both succeed, and what a killed writer left is recovered or cleaned on the
// next run (only a dead process's).
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <iterator>
#include <cstdio>
#include <barrier>
#include <filesystem>
#include <fstream>
#include <thread>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "mgrl/core/bundle.hpp"
#include "mgrl/core/files.hpp"
#include "test_support.hpp"

namespace mgrl::bundle_write_test {
namespace {

namespace fs = std::filesystem;

// A pid that belonged to a process that has exited (and been reaped).
pid_t deadPid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

void writeBundle(const fs::path& dir, const std::string& content) {
  writeBundleDirectory(dir, {{"data.txt", content}}, "{\"content\": \"" + content + "\"}", "test bundle");
}

std::string contentOf(const fs::path& dir) { return readFile(dir / "data.txt"); }

// `<stem>.<tag>-<pid>-<n>`, as a writer names its temporaries.
std::string sibling(std::string_view stem, std::string_view tag, long pid, std::string_view n) {
  return fmt::format("{}.{}-{}-{}", stem, tag, pid, n);
}

// How many entries `dir` holds: a bundle's folder has nothing beside it when its parent
// holds only it.
std::size_t entriesIn(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

void makeLeftover(const fs::path& path, bool withManifest, const std::string& content) {
  fs::create_directories(path);
  std::ofstream(path / "data.txt") << content;
  if (withManifest) std::ofstream(path / "manifest.json") << "{}";
}

TEST_CASE("a replaced bundle is never missing, even for a moment", "[bundle][harden]") {
  test::TempDir temp("bundle-replace");
  const fs::path dir = temp.path / "b";
  writeBundle(dir, "first");
  std::atomic<bool> done{false};
  std::atomic<int> missing{0};
  std::thread watcher([&] {
    std::error_code ec;
    while (!done)
      if (!fs::exists(dir / "manifest.json", ec)) ++missing;
  });
  for (int i = 0; i < 300; ++i) writeBundle(dir, fmt::format("version {}", i));
  done = true;
  watcher.join();
  CHECK(missing == 0);
  CHECK(contentOf(dir) == "version 299");
  // Nothing is left beside it.
  const std::size_t entries = entriesIn(temp.path);
  CHECK(entries == 1);
}

TEST_CASE("two writers of one bundle both succeed and leave one complete bundle", "[bundle][harden]") {
  test::TempDir temp("bundle-race");
  for (int round = 0; round < 300; ++round) {
    const fs::path dir = temp.path / fmt::format("b{}", round % 3);
    if (round % 2 == 0) fs::remove_all(dir);  // half the rounds race to create, half to replace
    std::atomic<int> failures{0};
    std::barrier start(2);
    auto write = [&](const std::string& content) {
      start.arrive_and_wait();  // both at once
      try {
        writeBundle(dir, content);
      } catch (const std::exception& e) {
        UNSCOPED_INFO(e.what());
        ++failures;
      }
    };
    std::thread a(write, "from a"), b(write, "from b");
    a.join();
    b.join();
    REQUIRE(failures == 0);
    const std::string content = contentOf(dir);
    CHECK((content == "from a" || content == "from b"));
  }
  const std::size_t entries = entriesIn(temp.path);
  CHECK(entries == 3);
}

TEST_CASE("two processes writing one bundle both succeed", "[bundle][harden]") {
  test::TempDir temp("bundle-processes");
  const fs::path dir = temp.path / "graph";
  for (int round = 0; round < 40; ++round) {
    if (round % 2 == 0) fs::remove_all(dir);  // half the rounds race to create, half to replace
    // Two children wait on a pipe, so that both start writing at once; each exits 1 if its
    // write fails.
    int gate[2];
    REQUIRE(::pipe(gate) == 0);
    auto child = [&](const char* who) {
      const pid_t pid = ::fork();
      if (pid != 0) return pid;
      char go = 0;
      if (::read(gate[0], &go, 1) != 1) ::_exit(2);
      try {
        writeBundle(dir, who);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "writer %s: %s\n", who, e.what());
        ::_exit(1);
      }
      ::_exit(0);
    };
    const pid_t a = child("a"), b = child("b");
    REQUIRE(::write(gate[1], "gg", 2) == 2);
    ::close(gate[0]);
    ::close(gate[1]);
    int statusA = -1, statusB = -1;
    ::waitpid(a, &statusA, 0);
    ::waitpid(b, &statusB, 0);
    REQUIRE((WIFEXITED(statusA) && WEXITSTATUS(statusA) == 0));
    REQUIRE((WIFEXITED(statusB) && WEXITSTATUS(statusB) == 0));
    const std::string content = contentOf(dir);
    CHECK((content == "a" || content == "b"));
  }
  const std::size_t entries = entriesIn(temp.path);
  CHECK(entries == 1);  // nothing left beside it
}

TEST_CASE("what a killed writer left is recovered or removed, a live writer's is kept", "[bundle][harden]") {
  test::TempDir temp("bundle-leftovers");
  const fs::path dir = temp.path / "policy";
  const pid_t dead = deadPid();

  SECTION("killed between the renames: the complete temporary comes back") {
    makeLeftover(temp.path / sibling("policy", "tmp", dead, "0"), true, "new");
    makeLeftover(temp.path / sibling("policy", "old", dead, "1"), true, "old");
    recoverBundleDirectory(dir, "manifest.json");
    CHECK(contentOf(dir) == "new");
    CHECK_FALSE(fs::exists(temp.path / sibling("policy", "old", dead, "1")));
  }
  SECTION("killed while writing: the old bundle comes back, the half-written one goes") {
    makeLeftover(temp.path / sibling("policy", "tmp", dead, "0"), false, "half");
    makeLeftover(temp.path / sibling("policy", "old", dead, "1"), true, "old");
    recoverBundleDirectory(dir, "manifest.json");
    CHECK(contentOf(dir) == "old");
    CHECK_FALSE(fs::exists(temp.path / sibling("policy", "tmp", dead, "0")));
  }
  SECTION("with the bundle in place, a dead writer's leftovers are removed when writing") {
    writeBundle(dir, "current");
    makeLeftover(temp.path / sibling("policy", "tmp", dead, "7"), false, "22 MB of a checkpoint");
    makeLeftover(temp.path / sibling("policy", "old", dead, "8"), true, "older");
    writeBundle(dir, "next");
    CHECK(contentOf(dir) == "next");
    const std::size_t entries = entriesIn(temp.path);
    CHECK(entries == 1);
  }
  SECTION("a live process's temporary and names that only look alike are kept") {
    writeBundle(dir, "current");
    const fs::path live = temp.path / sibling("policy", "tmp", ::getpid(), "99");
    makeLeftover(live, false, "being written");
    const fs::path other = temp.path / sibling("policy-2", "tmp", dead, "0");  // another bundle's
    makeLeftover(other, false, "x");
    const fs::path odd = temp.path / "policy.tmp-notapid";
    makeLeftover(odd, false, "x");
    recoverBundleDirectory(dir, "manifest.json");
    CHECK(fs::exists(live));
    CHECK(fs::exists(other));
    CHECK(fs::exists(odd));
    CHECK(contentOf(dir) == "current");
  }
}

// Found by the kill tests: train and compare check a folder by writing a probe named after
// their pid and removing it; a process killed in between left its probe for good.
TEST_CASE("a writability probe a dead process left is removed, a live process's is kept", "[files][harden]") {
  test::TempDir temp("probes");
  const pid_t dead = deadPid();
  const fs::path stale = temp.path / fmt::format(".mgrl-probe-{}", dead);
  // Not this process's own pid: its probe is the one the call writes and removes.
  const fs::path live = temp.path / fmt::format(".mgrl-probe-{}", ::getppid());
  const fs::path other = temp.path / fmt::format(".other.probe-{}", dead);  // another prefix's
  const fs::path odd = temp.path / ".mgrl-probe-12x";
  for (const fs::path& p : {stale, live, other, odd}) std::ofstream(p) << "x";

  CHECK(folderTakesNewFiles(temp.path, ".mgrl-probe-"));
  CHECK_FALSE(fs::exists(stale));
  CHECK(fs::exists(live));  // it may be probing now
  CHECK(fs::exists(other));
  CHECK(fs::exists(odd));
  CHECK(entriesIn(temp.path) == 3);  // and its own probe is gone
  CHECK_FALSE(folderTakesNewFiles(temp.path / "missing", ".mgrl-probe-"));
}

}  // namespace
}  // namespace mgrl::bundle_write_test
