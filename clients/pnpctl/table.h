#pragma once
// Columns aligned for a terminal, or comma-separated for other programs.

#include <cstdio>
#include <string>
#include <vector>

namespace pnp::pnpctl {

class Table {
 public:
  explicit Table(std::vector<std::string> header) : header_(std::move(header)) {}
  void add(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  void print(std::FILE* out) const;      // aligned, header underlined
  void print_csv(std::FILE* out) const;  // RFC 4180 quoting where needed

 private:
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

std::string fixed(double value, int decimals);
std::string duration_text(double seconds);  // "1m05s"

}  // namespace pnp::pnpctl
