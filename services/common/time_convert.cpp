#include "services/common/time_convert.h"

namespace pnp::services {

void to_proto(std::chrono::system_clock::time_point time, google::protobuf::Timestamp& out) {
  const auto ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(time.time_since_epoch()).count();
  out.set_seconds(ns / 1'000'000'000);
  out.set_nanos(static_cast<int>(ns % 1'000'000'000));
}

void to_proto(std::chrono::nanoseconds duration, google::protobuf::Duration& out) {
  const auto ns = duration.count();
  out.set_seconds(ns / 1'000'000'000);
  out.set_nanos(static_cast<int>(ns % 1'000'000'000));
}

double seconds_of(const google::protobuf::Duration& duration) {
  return static_cast<double>(duration.seconds()) + 1e-9 * static_cast<double>(duration.nanos());
}

}  // namespace pnp::services
