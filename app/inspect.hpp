#pragma once
/// \file
/// `mgrl inspect`: what is in motion files, as the motion stage reports it
/// (mgrl/motion/capture_report.hpp), printed as text.
#include <string>
#include <vector>

#include "mgrl/motion/capture_report.hpp"

namespace mgrl::app {

std::string inspectText(const std::vector<FileReport>& reports);

}  // namespace mgrl::app
