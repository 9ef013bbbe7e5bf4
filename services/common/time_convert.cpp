#include "services/common/time_convert.h"

#include <string>

#include "common/error.h"

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

std::chrono::system_clock::time_point from_proto(const google::protobuf::Timestamp& time,
                                                 std::string_view field) {
  constexpr long long kMaxSeconds = 253'402'300'799LL;  // 9999-12-31T23:59:59Z
  if (time.nanos() < 0 || time.nanos() >= 1'000'000'000 || time.seconds() < 0 ||
      time.seconds() > kMaxSeconds) {
    throw_invalid_argument(
        field, "a timestamp after 1970 (nanos in [0, 1e9))",
        std::to_string(time.seconds()) + " s " + std::to_string(time.nanos()) + " ns");
  }
  return std::chrono::system_clock::time_point(
      std::chrono::duration_cast<std::chrono::system_clock::duration>(
          std::chrono::seconds(time.seconds()) + std::chrono::nanoseconds(time.nanos())));
}

}  // namespace pnp::services
