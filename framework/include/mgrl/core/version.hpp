#pragma once
namespace mgrl {
/// The mgrl version, from the top-level CMakeLists.txt's project() (set where version.cpp
/// is compiled, so that no other file depends on it).
extern const char* const kVersion;
}  // namespace mgrl
