// SIGTERM and SIGINT handling is process-wide, so these cases have a binary of their own.
// Each installs the handlers itself, except the first, which needs them not installed yet.
#include <gtest/gtest.h>
#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "common/error.h"
#include "services/common/server_runtime.h"

namespace pnp::services {
namespace {

TEST(TerminationSignals, WaitingBeforeCatchingThemIsAnError) {
  EXPECT_THROW(wait_for_termination_signal(), Error);
}

TEST(TerminationSignals, ASigtermToTheProcessIsHandedToTheWaiter) {
  catch_termination_signals();
  std::jthread sender([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ::kill(::getpid(), SIGTERM);
  });
  EXPECT_EQ(wait_for_termination_signal(), SIGTERM);
}

// The kernel may deliver a process's signal to any thread: one landing on a busy worker
// still wakes the waiter. Under ThreadSanitizer, which runs handlers late, this also pins
// that the waiter is parked where the handler can run (a waiter in read() never woke).
TEST(TerminationSignals, ASigintLandingOnAnotherThreadWakesTheWaiter) {
  catch_termination_signals();
  std::atomic<bool> stop{false};
  std::jthread worker([&] {
    while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  std::jthread sender([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ::pthread_kill(worker.native_handle(), SIGINT);
  });
  EXPECT_EQ(wait_for_termination_signal(), SIGINT);
  stop.store(true);
}

TEST(TerminationSignals, EachSignalIsHandedOverOnce) {
  catch_termination_signals();  // a second call changes nothing
  ::kill(::getpid(), SIGTERM);
  ::kill(::getpid(), SIGINT);
  const int first = wait_for_termination_signal();
  const int second = wait_for_termination_signal();
  EXPECT_NE(first, second);
  EXPECT_TRUE((first == SIGTERM && second == SIGINT) || (first == SIGINT && second == SIGTERM));
}

}  // namespace
}  // namespace pnp::services
