#include "tests/core/store/power_loss_vfs.h"

#include <cstddef>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string_view>

namespace pnp::store::testing {
namespace {

// The file SQLite holds: ours, followed in the same allocation by the real VFS's file.
struct File {
  sqlite3_file base;
  PowerLossVfs* owner;
  sqlite3_file* real;
  char path[512];
};

File* as_file(sqlite3_file* f) {
  return reinterpret_cast<File*>(f);
}
sqlite3_file* real(sqlite3_file* f) {
  return as_file(f)->real;
}

int x_close(sqlite3_file* f) {
  return real(f)->pMethods ? real(f)->pMethods->xClose(real(f)) : SQLITE_OK;
}
int x_read(sqlite3_file* f, void* buf, int n, sqlite3_int64 offset) {
  return real(f)->pMethods->xRead(real(f), buf, n, offset);
}
int x_write(sqlite3_file* f, const void* buf, int n, sqlite3_int64 offset) {
  return real(f)->pMethods->xWrite(real(f), buf, n, offset);
}
int x_truncate(sqlite3_file* f, sqlite3_int64 size) {
  return real(f)->pMethods->xTruncate(real(f), size);
}
int x_sync(sqlite3_file* f, int flags) {
  const int rc = real(f)->pMethods->xSync(real(f), flags);
  if (rc == SQLITE_OK && as_file(f)->path[0] != '\0') as_file(f)->owner->synced(as_file(f)->path);
  return rc;
}
int x_file_size(sqlite3_file* f, sqlite3_int64* size) {
  return real(f)->pMethods->xFileSize(real(f), size);
}
int x_lock(sqlite3_file* f, int level) {
  return real(f)->pMethods->xLock(real(f), level);
}
int x_unlock(sqlite3_file* f, int level) {
  return real(f)->pMethods->xUnlock(real(f), level);
}
int x_check_reserved_lock(sqlite3_file* f, int* out) {
  return real(f)->pMethods->xCheckReservedLock(real(f), out);
}
int x_file_control(sqlite3_file* f, int op, void* arg) {
  return real(f)->pMethods->xFileControl(real(f), op, arg);
}
int x_sector_size(sqlite3_file* f) {
  return real(f)->pMethods->xSectorSize(real(f));
}
int x_device_characteristics(sqlite3_file* f) {
  return real(f)->pMethods->xDeviceCharacteristics(real(f));
}
int x_shm_map(sqlite3_file* f, int region, int size, int extend, void volatile** out) {
  return real(f)->pMethods->xShmMap(real(f), region, size, extend, out);
}
int x_shm_lock(sqlite3_file* f, int offset, int n, int flags) {
  return real(f)->pMethods->xShmLock(real(f), offset, n, flags);
}
void x_shm_barrier(sqlite3_file* f) {
  real(f)->pMethods->xShmBarrier(real(f));
}
int x_shm_unmap(sqlite3_file* f, int delete_flag) {
  return real(f)->pMethods->xShmUnmap(real(f), delete_flag);
}

// Version 2: shared memory (WAL) but no memory-mapped I/O, so every write goes through
// x_write.
constexpr sqlite3_io_methods kMethods = {2,
                                         x_close,
                                         x_read,
                                         x_write,
                                         x_truncate,
                                         x_sync,
                                         x_file_size,
                                         x_lock,
                                         x_unlock,
                                         x_check_reserved_lock,
                                         x_file_control,
                                         x_sector_size,
                                         x_device_characteristics,
                                         x_shm_map,
                                         x_shm_lock,
                                         x_shm_barrier,
                                         x_shm_unmap,
                                         nullptr,
                                         nullptr};

PowerLossVfs* owner_of(sqlite3_vfs* vfs) {
  return static_cast<PowerLossVfs*>(vfs->pAppData);
}

int x_open(sqlite3_vfs* vfs, const char* name, sqlite3_file* f, int flags, int* out_flags) {
  File* file = as_file(f);
  file->base.pMethods = nullptr;
  file->owner = owner_of(vfs);
  file->real = reinterpret_cast<sqlite3_file*>(reinterpret_cast<char*>(f) + sizeof(File));
  // Files without a name (temporary ones) or with a longer one are not tracked.
  const std::string_view path = name ? std::string_view(name) : std::string_view();
  const std::size_t kept = path.size() < sizeof(file->path) ? path.size() : 0;
  path.copy(file->path, kept);
  file->path[kept] = '\0';
  const int rc =
      file->owner->real()->xOpen(file->owner->real(), name, file->real, flags, out_flags);
  if (rc == SQLITE_OK) file->base.pMethods = &kMethods;
  return rc;
}

int x_delete(sqlite3_vfs* vfs, const char* name, int sync_dir) {
  owner_of(vfs)->deleted(name);
  return owner_of(vfs)->real()->xDelete(owner_of(vfs)->real(), name, sync_dir);
}

std::vector<char> contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

PowerLossVfs::PowerLossVfs(std::string name)
    : name_(std::move(name)), real_(sqlite3_vfs_find(nullptr)) {
  if (!real_) throw std::runtime_error("no default SQLite VFS");
  vfs_ = *real_;
  vfs_.pNext = nullptr;
  vfs_.szOsFile = static_cast<int>(sizeof(File)) + real_->szOsFile;
  vfs_.zName = name_.c_str();
  vfs_.pAppData = this;
  vfs_.xOpen = x_open;
  vfs_.xDelete = x_delete;
  if (sqlite3_vfs_register(&vfs_, 0) != SQLITE_OK) throw std::runtime_error("registering a VFS");
}

PowerLossVfs::~PowerLossVfs() {
  sqlite3_vfs_unregister(&vfs_);
}

void PowerLossVfs::synced(const std::string& path) {
  std::vector<char> image = contents(path);
  std::lock_guard lock(mutex_);
  durable_[path] = std::move(image);
  ++syncs_;
}

void PowerLossVfs::deleted(const std::string& path) {
  std::lock_guard lock(mutex_);
  durable_.erase(path);
}

int PowerLossVfs::syncs() const {
  std::lock_guard lock(mutex_);
  return syncs_;
}

void PowerLossVfs::power_cut(const std::filesystem::path& from,
                             const std::filesystem::path& to) const {
  std::lock_guard lock(mutex_);
  std::filesystem::create_directories(to);
  for (const auto& [path, image] : durable_) {
    const std::filesystem::path p(path);
    if (p.parent_path() != from) continue;
    std::ofstream(to / p.filename(), std::ios::binary)
        .write(image.data(), static_cast<std::streamsize>(image.size()));
  }
}

}  // namespace pnp::store::testing
