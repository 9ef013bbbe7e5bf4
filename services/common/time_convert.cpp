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

std::chrono::nanoseconds from_proto(const google::protobuf::Duration& duration,
                                    std::string_view field, std::chrono::seconds max) {
  const long long seconds = duration.seconds();
  const int nanos = duration.nanos();
  if (nanos < 0 || nanos >= 1'000'000'000 || seconds < 0 || seconds > max.count() ||
      (seconds == max.count() && nanos > 0)) {
    throw_invalid_argument(
        field, "a duration from 0 to " + std::to_string(max.count()) + " s (nanos in [0, 1e9))",
        std::to_string(seconds) + " s " + std::to_string(nanos) + " ns");
  }
  return std::chrono::seconds(seconds) + std::chrono::nanoseconds(nanos);
}

double seconds_of(const google::protobuf::Duration& duration) {
  return static_cast<double>(duration.seconds()) + 1e-9 * static_cast<double>(duration.nanos());
}

std::chrono::system_clock::time_point from_proto(const google::protobuf::Timestamp& time,
                                                 std::string_view field) {
  // The last whole second a nanosecond time point holds (2262-04-11); later ones would
  // overflow the conversion.
  constexpr long long kMaxSeconds = std::chrono::nanoseconds::max().count() / 1'000'000'000 - 1;
  if (time.nanos() < 0 || time.nanos() >= 1'000'000'000 || time.seconds() < 0 ||
      time.seconds() > kMaxSeconds) {
    throw_invalid_argument(
        field, "a timestamp from 1970 to 2262 (nanos in [0, 1e9))",
        std::to_string(time.seconds()) + " s " + std::to_string(time.nanos()) + " ns");
  }
  return std::chrono::system_clock::time_point(
      std::chrono::duration_cast<std::chrono::system_clock::duration>(
          std::chrono::seconds(time.seconds()) + std::chrono::nanoseconds(time.nanos())));
}

}  // namespace pnp::services
