#pragma once
// A SQLite VFS over the default one that models a power loss. Writes go to the real files
// at once (the connection reads back what it wrote, as through a page cache), and each
// file's durable image is what it held at its last xSync: what is on the platter. A power
// cut copies the durable images into another directory, which is what the machine would
// find after losing power at that instant had the OS kept none of the unsynced writes.
// A file never synced is absent there. Registered for the object's lifetime.

#include <sqlite3.h>

#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace pnp::store::testing {

class PowerLossVfs {
 public:
  explicit PowerLossVfs(std::string name);
  ~PowerLossVfs();
  PowerLossVfs(const PowerLossVfs&) = delete;
  PowerLossVfs& operator=(const PowerLossVfs&) = delete;

  const std::string& name() const { return name_; }
  // Writes the durable image of every file opened through this VFS under `from` into
  // `to`, with the same names.
  void power_cut(const std::filesystem::path& from, const std::filesystem::path& to) const;
  int syncs() const;

  // For the C callbacks.
  sqlite3_vfs* real() const { return real_; }
  void synced(const std::string& path);
  void deleted(const std::string& path);

 private:
  std::string name_;
  sqlite3_vfs* real_;
  sqlite3_vfs vfs_{};
  mutable std::mutex mutex_;
  std::map<std::string, std::vector<char>> durable_;
  int syncs_ = 0;
};

}  // namespace pnp::store::testing
