#include "store/checkpoint_import.h"

#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <vector>

#include "common/error.h"

namespace pnp::store {
namespace {

FinishedRun read_file(const CheckpointFile& file) {
  std::ifstream in(file.path, std::ios::binary);
  if (!in) throw Error(ErrorCode::kNotFound, file.path.string() + ": cannot read the checkpoint");
  FinishedRun run{{},
                  std::vector<std::uint8_t>{std::istreambuf_iterator<char>(in),
                                            std::istreambuf_iterator<char>()}};
  run.spec = {file.role,  file.algorithm,
              file.robot, file.object,
              0,          nlohmann::json{{"imported_from", file.path.filename().string()}}.dump(),
              "imported", std::nullopt};
  return run;
}

}  // namespace

std::int64_t import_checkpoint(Store& store, const CheckpointFile& file, bool promote) {
  const FinishedRun run = read_file(file);
  return store.import_finished(std::span<const FinishedRun>(&run, 1), promote).front();
}

std::vector<std::int64_t> import_hierarchy(Store& store, const std::filesystem::path& dir,
                                           const std::string& robot, const std::string& object) {
  std::vector<FinishedRun> runs;
  for (const char* role : {"approach", "manipulate", "retract", "hlc"}) {
    runs.push_back(read_file({role, std::string(role) == "hlc" ? "a3c" : "ddpg_her", robot, object,
                              dir / (std::string(role) + ".ckpt")}));
  }
  return store.import_finished(runs, true);
}

}  // namespace pnp::store
