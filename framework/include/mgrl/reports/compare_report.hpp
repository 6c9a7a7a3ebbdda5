#pragma once
/// \file
/// What `mgrl compare` writes with --report DIR: results.json, results.csv (one
/// row per run), curves.csv (every curve point of every run) and index.html, self-contained
/// (opens from disk, loads nothing), with SVG plots drawn here.
#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace mgrl {

/// A metric's value as the report shows it to people, three significant digits in the
/// metric's unit (compareMetrics() keys): shares as percentages ("95.0 %"), seconds
/// ("3.68 s", "12.3 ms"), microseconds ("12.3 us"), counts with a prefix ("66.3 M"), bytes
/// ("11.0 MB"); other values plain ("0.0123"), in scientific notation only when below
/// 0.001 or from a million up. `delta` formats a spread (a standard deviation) alike, a
/// share in percentage points without the sign, a time in seconds however short.
std::string reportNumber(std::string_view key, double value, bool delta = false);

/// Writes the four files into `dir` (each atomically). Throws mgrl::Error on I/O failure.
void writeCompareReport(const std::filesystem::path& dir, const nlohmann::json& report);

}  // namespace mgrl
