// Writes the service_requests fuzz target's seed inputs from their text form:
//   write_service_seeds tests/fuzz/service_requests_seeds.txt tests/fuzz/corpus/service_requests
// Each line "INDEX live|ids TYPE | request | request ..." becomes one file: the selector
// byte (INDEX, plus 0x80 for live), then the binary request, or for a stream each request
// after its 2-byte little-endian length. Readable seeds, reproducible inputs.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/dynamic_message.h>
#include <google/protobuf/message.h>
#include <google/protobuf/text_format.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "pnp/policy/v1/policy_service.pb.h"
#include "pnp/robot/v1/robot_controller.pb.h"
#include "pnp/sim/v1/sim_service.pb.h"
#include "pnp/train/v1/train_service.pb.h"

namespace {

// The streams' request types: their inputs carry length-prefixed messages.
bool is_stream(const std::string& type) {
  return type == "pnp.sim.v1.StreamRolloutRequest" ||
         type == "pnp.policy.v1.PredictSessionRequest" ||
         type == "pnp.robot.v1.StreamPoseTargetsRequest";
}

// Names the services' proto files, so the linker keeps them in the generated pool.
void register_protos() {
  pnp::sim::v1::CreateEnvRequest::descriptor();
  pnp::policy::v1::PredictRequest::descriptor();
  pnp::train::v1::CreateTrainingRunRequest::descriptor();
  pnp::robot::v1::AcquireLeaseRequest::descriptor();
}

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(line);
  for (std::string part; std::getline(in, part, separator);) parts.push_back(part);
  return parts;
}

std::string seed_bytes(const std::string& line, int number) {
  const auto parts = split(line, '|');
  std::istringstream head(parts.at(0));
  int index = 0;
  std::string mode, type;
  if (!(head >> index >> mode >> type) || index < 0 || index > 31 ||
      (mode != "live" && mode != "ids"))
    throw std::runtime_error("line " + std::to_string(number) +
                             ": expected \"INDEX live|ids TYPE | request ...\"");
  const auto* descriptor =
      google::protobuf::DescriptorPool::generated_pool()->FindMessageTypeByName(type);
  if (!descriptor)
    throw std::runtime_error("line " + std::to_string(number) + ": unknown type " + type);
  std::string out(1, static_cast<char>(index | (mode == "live" ? 0x80 : 0)));
  for (std::size_t p = 1; p < parts.size(); ++p) {
    std::unique_ptr<google::protobuf::Message> message(
        google::protobuf::MessageFactory::generated_factory()->GetPrototype(descriptor)->New());
    if (!google::protobuf::TextFormat::ParseFromString(parts[p], message.get()))
      throw std::runtime_error("line " + std::to_string(number) + ": not a " + type + ": " +
                               parts[p]);
    const std::string bytes = message->SerializeAsString();
    if (is_stream(type)) {
      out.push_back(static_cast<char>(bytes.size() & 0xff));
      out.push_back(static_cast<char>(bytes.size() >> 8));
    }
    out += bytes;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: write_service_seeds SEEDS.txt OUT_DIR\n";
    return 2;
  }
  try {
    register_protos();
    std::ifstream in(argv[1]);
    if (!in) throw std::runtime_error(std::string("cannot read ") + argv[1]);
    std::filesystem::create_directories(argv[2]);
    int number = 0, written = 0;
    for (std::string line; std::getline(in, line);) {
      ++number;
      if (line.empty() || line[0] == '#') continue;
      char name[32];
      std::snprintf(name, sizeof name, "seed_%02d", ++written);
      std::ofstream(std::filesystem::path(argv[2]) / name, std::ios::binary)
          << seed_bytes(line, number);
    }
    std::cout << "wrote " << written << " seeds to " << argv[2] << "\n";
  } catch (const std::exception& e) {
    std::cerr << "write_service_seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
