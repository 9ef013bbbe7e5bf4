// pnp-import: brings a hierarchy trained with `pnp-train --out DIR` (approach.ckpt,
// manipulate.ckpt, retract.ckpt, hlc.ckpt) into a store as finished runs and promotes it,
// all in one transaction, so an inference service reading that store serves it at its next
// reload. The checkpoints themselves are verified by the inference service when it loads
// them; here only their presence is checked, before anything is written.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "common/error.h"
#include "services/store/remote_store.h"
#include "services/store/store_flags.h"
#include "sim/object_shape.h"
#include "sim/robot.h"
#include "store/checkpoint_import.h"
#include "store/run_store.h"
#include "tools/common/cli.h"

int main(int argc, char** argv) {
  CLI::App app{"Import a trained hierarchy into a store and promote it", "pnp-import"};
  std::string db, dir, robot = "panda", object = "block";
  bool json = false;
  auto* db_option = app.add_option("--db", db, "the SQLite store (created if missing)");
  pnp::services::RemoteStoreFlags store_flags;
  pnp::services::add_remote_store_flags(app, store_flags, db_option);
  app.add_option("--hierarchy", dir,
                 "a directory holding approach.ckpt, manipulate.ckpt, retract.ckpt, hlc.ckpt")
      ->required();
  app.add_option("--robot", robot, "the robot it was trained on: fetch or panda")
      ->capture_default_str();
  app.add_option("--object", object, "the object it was trained on: block, small_block, cylinder")
      ->capture_default_str();
  app.add_flag("--json", json, "print the new checkpoint ids as one JSON object");
  return pnp::tools::run_tool(app, argc, argv, [&] {
    if (db.empty() != store_flags.remote())
      pnp::throw_invalid_argument("--db", "a store file, or --store host:port", "neither");
    pnp::sim::parse_robot(robot, "--robot");
    pnp::sim::parse_object(object, "--object");
    for (const char* role : {"approach", "manipulate", "retract", "hlc"}) {
      const auto file = std::filesystem::path(dir) / (std::string(role) + ".ckpt");
      if (!std::filesystem::is_regular_file(file))
        pnp::throw_invalid_argument("--hierarchy",
                                    "a directory with approach, manipulate, retract and hlc .ckpt",
                                    file.string() + " missing");
    }
    const std::unique_ptr<pnp::store::Store> store =
        store_flags.remote()
            ? pnp::services::remote_store_opener(store_flags.address, store_flags.tls)()
            : std::make_unique<pnp::store::RunStore>(db);
    const auto ids = pnp::store::import_hierarchy(*store, dir, robot, object);
    if (json) {
      std::printf(
          "%s\n",
          nlohmann::json{
              {"approach", ids[0]}, {"manipulate", ids[1]}, {"retract", ids[2]}, {"hlc", ids[3]}}
              .dump()
              .c_str());
      return;
    }
    std::printf("promoted checkpoints approach %lld, manipulate %lld, retract %lld, hlc %lld\n",
                static_cast<long long>(ids[0]), static_cast<long long>(ids[1]),
                static_cast<long long>(ids[2]), static_cast<long long>(ids[3]));
  });
}
