#include "store/checkpoint_import.h"

#include <fstream>
#include <iterator>
#include <vector>

#include "common/error.h"

namespace pnp::store {

std::int64_t import_checkpoint(RunStore& store, const CheckpointFile& file, bool promote) {
  std::ifstream in(file.path, std::ios::binary);
  if (!in) throw Error(ErrorCode::kNotFound, file.path.string() + ": cannot read the checkpoint");
  const std::vector<std::uint8_t> blob{std::istreambuf_iterator<char>(in),
                                       std::istreambuf_iterator<char>()};
  const RunRecord run = store.create_run(
      {file.role, file.algorithm, file.robot, file.object, 0,
       "{\"imported_from\": \"" + file.path.filename().string() + "\"}", "imported", std::nullopt});
  // Finished at once, so that no training service takes it for an interrupted run to
  // resume (a crash before the checkpoint is saved leaves a finished run without one).
  store.set_state(run.id, RunState::kSucceeded);
  const std::int64_t id = store.save_checkpoint(run.id, 0, 0.0, blob).id;
  if (promote) store.promote(id);
  return id;
}

void import_hierarchy(RunStore& store, const std::filesystem::path& dir, const std::string& robot,
                      const std::string& object) {
  for (const char* role : {"approach", "manipulate", "retract", "hlc"}) {
    import_checkpoint(store,
                      {role, std::string(role) == "hlc" ? "a3c" : "ddpg_her", robot, object,
                       dir / (std::string(role) + ".ckpt")},
                      true);
  }
}

}  // namespace pnp::store
