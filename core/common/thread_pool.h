#pragma once
// A fixed pool of worker threads for data-parallel loops. parallel_for splits [0, n) into
// one contiguous chunk per thread; the result of each index must not depend on which
// thread ran it, which is what keeps vectorised environments deterministic.

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace pnp {

class ThreadPool {
 public:
  // threads == 0 means one per hardware thread. The calling thread takes part in every
  // loop, so a pool of T threads starts T - 1 workers.
  explicit ThreadPool(std::size_t threads = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  std::size_t size() const { return workers_.size() + 1; }

  // Calls fn(i) for every i in [0, n) and returns when all are done. The first exception
  // thrown by fn is rethrown here after every chunk has finished.
  void parallel_for(std::size_t n, const std::function<void(std::size_t)>& fn);

 private:
  void worker_loop(std::size_t worker_index);
  void run_chunk(std::size_t chunk, std::size_t chunks);

  std::vector<std::jthread> workers_;
  std::mutex mutex_;
  std::condition_variable work_ready_;
  std::condition_variable work_done_;
  const std::function<void(std::size_t)>* job_ = nullptr;
  std::size_t job_size_ = 0;
  std::size_t generation_ = 0;
  std::size_t pending_ = 0;
  bool stopping_ = false;
  std::exception_ptr first_error_;
};

}  // namespace pnp
