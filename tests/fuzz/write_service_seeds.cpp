// Writes the service_requests fuzz target's seed inputs from their text form:
//   write_service_seeds tests/fuzz/service_requests_seeds.txt tests/fuzz/corpus/service_requests
// With --check first it writes nothing and fails if the directory's seed_* files are not
// exactly those the text gives (ctest runs it so, so an edited seed cannot go stale).
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
#include <utility>
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

// The seed files the text describes, in order: seed_01, seed_02, ...
std::vector<std::pair<std::string, std::string>> read_seeds(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::vector<std::pair<std::string, std::string>> seeds;
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    char name[32];
    std::snprintf(name, sizeof name, "seed_%02zu", seeds.size() + 1);
    seeds.emplace_back(name, seed_bytes(line, number));
  }
  return seeds;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// Names each difference between the directory's seed_* files and `seeds`; 0 if none.
int check(const std::vector<std::pair<std::string, std::string>>& seeds,
          const std::filesystem::path& dir) {
  int stale = 0;
  for (const auto& [name, bytes] : seeds) {
    if (!std::filesystem::exists(dir / name) || read_file(dir / name) != bytes) {
      std::cerr << "write_service_seeds: " << (dir / name).string()
                << " is missing or differs from its line in the seeds text\n";
      ++stale;
    }
  }
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("seed_", 0) != 0) continue;  // crash reproducers and found inputs stay
    bool known = false;
    for (const auto& seed : seeds) known = known || seed.first == name;
    if (!known) {
      std::cerr << "write_service_seeds: " << entry.path().string()
                << " has no line in the seeds text\n";
      ++stale;
    }
  }
  return stale;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  const bool check_only = !args.empty() && args[0] == "--check";
  if (check_only) args.erase(args.begin());
  if (args.size() != 2) {
    std::cerr << "usage: write_service_seeds [--check] SEEDS.txt DIR\n";
    return 2;
  }
  try {
    register_protos();
    const auto seeds = read_seeds(args[0]);
    const std::filesystem::path dir(args[1]);
    if (check_only) {
      if (const int stale = check(seeds, dir); stale > 0) {
        std::cerr << stale << " stale seed file(s): run write_service_seeds " << args[0] << " "
                  << args[1] << "\n";
        return 1;
      }
      std::cout << seeds.size() << " seeds in " << args[1] << " match " << args[0] << "\n";
      return 0;
    }
    std::filesystem::create_directories(dir);
    for (const auto& [name, bytes] : seeds) std::ofstream(dir / name, std::ios::binary) << bytes;
    std::cout << "wrote " << seeds.size() << " seeds to " << args[1] << "\n";
  } catch (const std::exception& e) {
    std::cerr << "write_service_seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
