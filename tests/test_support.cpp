#include "test_support.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fstream>

#include <fmt/format.h>

#include <catch2/catch.hpp>

#include "mgrl/core/data_paths.hpp"

namespace mgrl::test {

std::filesystem::path mocap() {
  const std::filesystem::path dir = dataDirectory();
  INFO("motion capture folder " << dir << " (set MGRL_DATA to move it)");
  REQUIRE(std::filesystem::is_directory(dir / "cmu"));
  return dir;
}

std::filesystem::path testData() { return MGRL_TEST_PATH_DATA; }
const char* sourceDirectory() { return MGRL_TEST_PATH_SOURCE; }
const char* mgrlBinary() { return MGRL_TEST_PATH_BINARY; }

TempDir::TempDir(std::string_view tag) {
  static int counter = 0;
  path = std::filesystem::temp_directory_path() / fmt::format("mgrl-{}-{}-{}", tag, ::getpid(), counter++);
  std::filesystem::remove_all(path);
  std::filesystem::create_directories(path);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path, ignored);
}

std::filesystem::path sharedResult(const std::string& name,
                                   const std::function<void(const std::filesystem::path&)>& make) {
  namespace fs = std::filesystem;
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const auto built = fs::last_write_time(exe).time_since_epoch().count();
  const fs::path root = exe.parent_path() / "shared-results";
  const fs::path dir = root / fmt::format("{}", built);
  if (!fs::is_directory(dir)) {
    fs::create_directories(dir);
    std::error_code ignored;  // a folder another process removes first is fine
    for (const fs::directory_entry& e : fs::directory_iterator(root, ignored))
      if (e.path() != dir) fs::remove_all(e.path(), ignored);
  }
  const fs::path folder = dir / name, done = dir / (name + ".done");
  const std::string lockPath = (dir / (name + ".lock")).string();
  const int lock = ::open(lockPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  REQUIRE(lock >= 0);
  REQUIRE(::flock(lock, LOCK_EX) == 0);  // released when the descriptor closes, also on a throw
  struct Close {
    int fd;
    ~Close() { ::close(fd); }
  } closeLock{lock};
  if (!fs::exists(done)) {
    fs::remove_all(folder);  // what a killed maker left
    fs::create_directories(folder);
    make(folder);
    std::ofstream(done) << "done\n";
  }
  return folder;
}

LoadedMotion loadMocap(const std::string& relative, const LoadOptions& options) {
  return loadMotion(mocap() / relative, options);
}

// A small humanoid with the given joint names (pelvis, spine, head, then per side
// shoulder, forearm, hand, hip, knee, ankle, toe).
Skeleton humanoid(const std::vector<std::string>& names) {
  std::vector<Joint> joints;
  auto add = [&](const std::string& name, int parent, Eigen::Vector3d offset) {
    Joint j;
    j.name = name;
    j.parent = parent;
    j.offset = offset;
    joints.push_back(j);
    return static_cast<int>(joints.size() - 1);
  };
  const int pelvis = add(names[0], -1, {0, 1, 0});
  const int spine = add(names[1], pelvis, {0, 0.3, 0});
  const int head = add(names[2], spine, {0, 0.3, 0});
  joints[static_cast<std::size_t>(head)].endSite = Eigen::Vector3d(0, 0.2, 0);
  for (int s = 0; s < 2; ++s) {
    const double x = s == 0 ? 1 : -1;
    const std::size_t o = 3 + static_cast<std::size_t>(s) * 7;
    const int shoulder = add(names[o], spine, {x * 0.2, 0.2, 0});
    const int forearm = add(names[o + 1], shoulder, {x * 0.3, 0, 0});
    const int hand = add(names[o + 2], forearm, {x * 0.25, 0, 0});
    joints[static_cast<std::size_t>(hand)].endSite = Eigen::Vector3d(x * 0.08, 0, 0);
    const int hip = add(names[o + 3], pelvis, {x * 0.1, 0, 0});
    const int knee = add(names[o + 4], hip, {0, -0.45, 0});
    const int ankle = add(names[o + 5], knee, {0, -0.45, 0});
    const int toe = add(names[o + 6], ankle, {0, -0.07, 0.12});
    joints[static_cast<std::size_t>(toe)].endSite = Eigen::Vector3d(0, 0, 0.05);
  }
  return Skeleton(joints);
}


}  // namespace mgrl::test

namespace mgrl::test {

std::vector<std::string> humanoidNames() {
  return {"Hips", "Spine", "Head", "LeftArm", "LeftForeArm", "LeftHand", "LeftUpLeg", "LeftLeg", "LeftFoot",
          "LeftToeBase", "RightArm", "RightForeArm", "RightHand", "RightUpLeg", "RightLeg", "RightFoot",
          "RightToeBase"};
}

}  // namespace mgrl::test
