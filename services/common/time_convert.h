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
// INVALID_ARGUMENT naming `field` for nanos outside [0, 1e9) or seconds beyond year 9999
// (protobuf's valid range).
std::chrono::system_clock::time_point from_proto(const google::protobuf::Timestamp& time,
                                                 std::string_view field);

}  // namespace pnp::services
