#pragma once
// google.protobuf Timestamp and Duration <-> std::chrono, defined once for every service
// and client.

#include <google/protobuf/duration.pb.h>
#include <google/protobuf/timestamp.pb.h>

#include <chrono>

namespace pnp::services {

void to_proto(std::chrono::system_clock::time_point time, google::protobuf::Timestamp& out);
void to_proto(std::chrono::nanoseconds duration, google::protobuf::Duration& out);
double seconds_of(const google::protobuf::Duration& duration);

}  // namespace pnp::services
