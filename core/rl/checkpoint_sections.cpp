#include "rl/checkpoint_sections.h"

#include "common/error.h"

namespace pnp::rl {

void write_meta(nn::CheckpointWriter& w, const nlohmann::json& meta) {
  w.add_text("meta", meta.dump());
}

nlohmann::json read_meta(const nn::CheckpointReader& r, const std::string& kind) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(r.text("meta"));
  } catch (const nlohmann::json::exception& e) {
    throw Error(ErrorCode::kDataLoss, std::string("checkpoint: unreadable metadata: ") + e.what());
  }
  // Anything but the expected string (a number, a missing key, metadata that is not an
  // object) is another kind of file.
  const auto field = j.is_object() ? j.find("kind") : j.end();
  const bool found = field != j.end() && field->is_string();
  if (!found || field->get_ref<const std::string&>() != kind) {
    throw_invalid_argument("checkpoint kind", kind,
                           found ? "\"" + field->get_ref<const std::string&>() + "\""
                                 : (field == j.end() ? std::string("none") : field->dump()));
  }
  return j;
}

void require_float_section(const nn::CheckpointReader& r, const std::string& name,
                           std::size_t count) {
  const std::size_t bytes = r.bytes(name).size();
  if (bytes != count * sizeof(float)) {
    throw Error(ErrorCode::kDataLoss, "checkpoint: section \"" + name + "\" holds " +
                                          std::to_string(bytes / sizeof(float)) +
                                          " values, expected " + std::to_string(count));
  }
}

void write_normalizer(nn::CheckpointWriter& w, const std::string& name, const nn::Normalizer& n) {
  w.add_doubles(name + ".sum", n.sums());
  w.add_doubles(name + ".sumsq", n.sums_of_squares());
  const double count = n.count();
  w.add_doubles(name + ".count", std::span<const double>(&count, 1));
}

void read_normalizer(const nn::CheckpointReader& r, const std::string& name, nn::Normalizer& n) {
  const std::size_t size = n.sums().size();
  const auto sums = r.doubles(name + ".sum", size);
  const auto sumsq = r.doubles(name + ".sumsq", size);
  const auto count = r.doubles(name + ".count", 1);
  n.restore(sums, sumsq, count[0]);
}

}  // namespace pnp::rl
