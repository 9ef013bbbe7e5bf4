#pragma once
// google.protobuf Timestamp and Duration <-> std::chrono, defined once for every service
// and client.

#include <google/protobuf/duration.pb.h>
#include <google/protobuf/timestamp.pb.h>

#include <chrono>
#include <string_view>

namespace pnp::services {

void to_proto(std::chrono::system_clock::time_point time, google::protobuf::Timestamp& out);
void to_proto(std::chrono::nanoseconds duration, google::protobuf::Duration& out);
double seconds_of(const google::protobuf::Duration& duration);
// INVALID_ARGUMENT naming `field` unless 0 <= duration <= max with nanos in [0, 1e9):
// checked before any conversion, which a huge value would overflow.
std::chrono::nanoseconds from_proto(const google::protobuf::Duration& duration,
                                    std::string_view field, std::chrono::seconds max);
// INVALID_ARGUMENT naming `field` for nanos outside [0, 1e9) or a time before 1970 or
// after 2262 (what a nanosecond time point holds).
std::chrono::system_clock::time_point from_proto(const google::protobuf::Timestamp& time,
                                                 std::string_view field);

}  // namespace pnp::services
