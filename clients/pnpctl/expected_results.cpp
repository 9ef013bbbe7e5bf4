#include "clients/pnpctl/expected_results.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "common/error.h"

namespace pnp::pnpctl {
namespace {

constexpr const char* kRoles[] = {"approach", "manipulate", "retract", "hlc"};
// The settings a measurement was made with; a run with others is not compared.
constexpr const char* kSettings[] = {"robot", "object", "world", "actuation", "seed", "gemm_path"};

nlohmann::json read_expected(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(ErrorCode::kNotFound, "--expected: cannot read " + path);
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, false);
  if (!doc.is_object() || !doc.contains("measured") || !doc.at("measured").is_array())
    throw_invalid_argument("--expected", "a JSON object with a \"measured\" list", path);
  return doc;
}

bool same_settings(const nlohmann::json& measured, const nlohmann::json& results) {
  for (const char* key : kSettings)
    if (!measured.contains(key) || !results.contains(key) || measured.at(key) != results.at(key))
      return false;
  return true;
}

long long steps_of(const nlohmann::json& results, const std::string& role) {
  for (const auto& r : results.at("roles")) {
    if (r.at("role") != role) continue;
    return r.at("steps_to_target").is_null() ? -1 : r.at("steps_to_target").get<long long>();
  }
  return -1;
}

std::string fmt_steps(long long steps) {
  return steps < 0 ? std::string("not reached") : std::to_string(steps);
}

// One line per figure that differs; empty when every one matches.
std::string differences(const nlohmann::json& expected, const nlohmann::json& results) {
  std::string out;
  for (const char* role : kRoles) {
    const long long want = expected.at("steps_to_target").value(role, -1LL);
    const long long got = steps_of(results, role);
    if (want != got) {
      out += std::string("  ") + role + ": " + fmt_steps(got) + " steps to target (expected " +
             fmt_steps(want) + ")\n";
    }
  }
  const double want = expected.at("held_out_success").get<double>();
  const double got = results.at("held_out").at("success_rate").get<double>();
  if (std::abs(want - got) > 1e-9) {
    char line[96];
    std::snprintf(line, sizeof line, "  held-out success: %.3f (expected %.3f)\n", got, want);
    out += line;
  }
  return out;
}

std::string describe(const nlohmann::json& measured) {
  return "commit " + measured.value("commit", std::string("?")) + ", " +
         measured.value("gemm_path", std::string("?")) + " GEMM path, " +
         measured.value("kernel", std::string("?"));
}

std::string gateway_line(const nlohmann::json& measured) {
  if (!measured.contains("gateway")) return {};
  return "  then, with the Panda, the robot gateway: " + measured.at("gateway").get<std::string>() +
         " episodes expected\n";
}

}  // namespace

std::string compare_with_expected(const nlohmann::json& results, const std::string& expected_file) {
  const nlohmann::json doc = read_expected(expected_file);
  std::string differing;
  for (const auto& measured : doc.at("measured")) {
    if (!same_settings(measured, results)) continue;
    const std::string diff = differences(measured, results);
    if (diff.empty()) {
      return "as expected: exactly the figures " + expected_file + " gives for this job (" +
             describe(measured) + ")\n" + gateway_line(measured);
    }
    differing += "  against " + describe(measured) + ":\n" + diff;
  }
  if (!differing.empty()) {
    const std::string commit = results.value("code_commit", std::string("?"));
    return "differs from the figures " + expected_file + " gives for this job:\n" + differing +
           "  (this build is at commit " + commit +
           ": on the commit, path and OpenBLAS kernel of a row, a difference is a defect to "
           "report; on another commit the code between may have changed what is learned)\n";
  }
  return "no figures in " + expected_file + " for these settings (robot " +
         results.value("robot", std::string("?")) + ", world " +
         results.value("world", std::string("?")) + ", seed " +
         std::to_string(results.value("seed", 0ULL)) + ", " +
         results.value("gemm_path", std::string("?")) +
         " GEMM path): the same seed reproduces a run only with the same commit, flags, GEMM "
         "path and OpenBLAS kernel\n";
}

}  // namespace pnp::pnpctl
