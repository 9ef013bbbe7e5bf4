#pragma once
// What a user checks their install against: the figures docs/RESULTS.md gives for the main
// job (scripts/run), per GEMM path and commit, checked in as JSON
// (docs/results/expected/main_job.json). On the same commit, seed, flags and GEMM path
// (and OpenBLAS kernel, on the openblas path) a run gives exactly these numbers; on another
// path or commit the curve differs (docs/LEARNING.md, "GEMM paths") and the comparison says
// by how much, rather than leaving the user to wonder whether the install is broken.

#include <nlohmann/json.hpp>
#include <string>

namespace pnp::pnpctl {

// `results` as `pnpctl pipeline --json-out` writes them. Returns the lines to print: the
// expected figures for this run's settings and GEMM path and whether the run matched them,
// or why there are none to compare with. INVALID_ARGUMENT naming the file for one that is
// not the expected shape.
std::string compare_with_expected(const nlohmann::json& results, const std::string& expected_file);

}  // namespace pnp::pnpctl
