#include "mgrl/motion/motion_io.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "mgrl/motion/asf_amc.hpp"
#include "mgrl/motion/roles.hpp"

namespace mgrl {
namespace {

std::string lowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// The CMU subject number a file name carries: "13" for the motion "13_17" (motion) or the
// skeleton "13"; empty for names that do not follow CMU's numbering.
std::string cmuSubject(const std::string& stem, bool motion) {
  const std::string number = motion ? stem.substr(0, stem.find('_')) : stem;
  if (number.empty() || (motion && number.size() == stem.size())) return {};
  for (char c : number)
    if (!std::isdigit(static_cast<unsigned char>(c))) return {};
  return number;
}

}  // namespace

void writeBvhFile(const std::filesystem::path& path, const Motion& motion, const BvhWriteOptions& options) {
  std::ostringstream out;
  writeBvh(out, motion, options);
  writeFileAtomically(path, out.str());
}

std::filesystem::path defaultAsfFor(const std::filesystem::path& amc) {
  const std::string stem = amc.stem().string();
  return amc.parent_path() / (stem.substr(0, stem.find('_')) + ".asf");
}

LoadedMotion loadMotion(const std::filesystem::path& path, const LoadOptions& options) {
  const std::string source = path.string();
  const std::string ext = lowerExtension(path);
  std::optional<Motion> raw;
  LengthUnit units = options.units;
  double metresPerUnit = 1.0;
  if (ext == ".bvh") {
    const std::string text = readFile(path);
    raw.emplace(parseBvh(text, source, options.warn));
    if (units == LengthUnit::Auto) units = detectLengthUnit(estimateRestHeight(raw->skeleton()), source);
    metresPerUnit = metresPer(units);
  } else if (ext == ".amc") {
    const std::filesystem::path asfPath = options.asf.empty() ? defaultAsfFor(path) : options.asf;
    std::error_code ec;
    if (!std::filesystem::exists(asfPath, ec))
      throw Error(fmt::format("{}: expected its skeleton {}, found no such file; pass --asf FILE", source,
                              asfPath.string()));
    if (!options.asf.empty() && options.warn) {
      // Every CMU subject's ASF has the same bones and channels, so another subject's loads
      // without an error, with the wrong person's bone lengths. The names tell.
      const std::string subject = cmuSubject(path.stem().string(), true), asfSubject = cmuSubject(asfPath.stem().string(), false);
      if (!subject.empty() && !asfSubject.empty() && subject != asfSubject)
        options.warn(fmt::format("{}: expected the skeleton of subject {} ({}), found {} (subject {}): its bones and "
                                 "channels match, its bone lengths are another person's",
                                 source, subject, defaultAsfFor(path).filename().string(),
                                 asfPath.filename().string(), asfSubject));
    }
    const AsfSkeleton asf = parseAsf(readFile(asfPath), asfPath.string());
    raw.emplace(parseAmc(readFile(path), source, asf, 1.0 / options.amcFps));
    if (units == LengthUnit::Auto) {
      // The ASF states its unit: lengths are inches times `length` (CMU's 0.45).
      metresPerUnit = 0.0254 / asf.lengthPerInch;
      units = std::abs(asf.lengthPerInch - 0.45) < 1e-9 ? LengthUnit::Cmu
              : std::abs(asf.lengthPerInch - 1.0) < 1e-9 ? LengthUnit::Inch
                                                          : LengthUnit::Auto;
    } else {
      metresPerUnit = metresPer(units);
    }
  } else if (ext == ".asf") {
    throw Error(fmt::format("{}: expected a motion (.bvh or .amc), found an ASF skeleton; give its .amc", source));
  } else {
    throw Error(fmt::format("{}: expected a .bvh or .amc file, found extension '{}'", source, ext));
  }
  const double fileFps = raw->fps();
  Motion motion = raw->scaled(metresPerUnit);
  if (options.fps > 0 && std::abs(options.fps - fileFps) > 1e-9) motion = resample(motion, options.fps);
  return {std::move(motion), units, fileFps};
}

}  // namespace mgrl
