// The main of the test binaries that ctest also runs with each GEMM path forced
// (PNP_GEMM=avx512|avx2|openblas, tests/CMakeLists.txt). On a CPU that lacks the forced
// path every test is skipped with the reason, so one test list holds on every x86-64
// machine; an unknown PNP_GEMM value still fails, naming the variable.

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>

#include "common/error.h"
#include "nn/cpu_features.h"
#include "nn/gemm_path.h"

namespace {

class ForcedGemmPath : public ::testing::Environment {
 public:
  void SetUp() override {
    const char* requested = std::getenv("PNP_GEMM");
    const auto path = pnp::nn::parse_gemm_path(requested ? requested : "");
    const pnp::nn::CpuFeatures cpu = pnp::nn::detect_cpu_features();
    if (path && !pnp::nn::cpu_supports(*path, cpu)) {
      GTEST_SKIP() << "PNP_GEMM=" << requested << ": this CPU cannot run that path ("
                   << pnp::nn::describe(cpu) << ")";
    }
    try {
      std::printf("GEMM path: %s\n",
                  std::string(pnp::nn::gemm_path_name(pnp::nn::active_gemm_path())).c_str());
    } catch (const pnp::Error& e) {
      FAIL() << e.what();
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  // GoogleTest takes ownership of the environment.
  ::testing::AddGlobalTestEnvironment(std::make_unique<ForcedGemmPath>().release());
  return RUN_ALL_TESTS();
}
