#include "apps/hnn/commands/help_format.h"

#include <utility>

namespace hnn::app {

std::string text_metavar(std::string_view name) {
  static const std::pair<const char*, const char*> kByName[] = {
      {"out", "PATH"},          {"data", "FILE"},          {"states", "FILE"},
      {"hamiltonian", "EXPR"},  {"state", "V0,V1,.."},     {"scheduler", "ADDRESS"},
      {"time", "COLUMN"},       {"trajectory", "COLUMN"},  {"coords", "COLUMNS"},
      {"momenta", "COLUMNS"},   {"velocities", "COLUMNS"}, {"derivatives", "COLUMNS"},
      {"tasks", "NAMES"},       {"models", "NAMES"},       {"loss", "NAMES"},
      {"integrators", "NAMES"}, {"integrator", "NAME"},    {"format", "NAME"},
      {"settings", "JSON"},     {"sample", "BOX"},         {"energy", "LO:HI"}};
  for (const auto& [option, metavar] : kByName) {
    if (name == option) return metavar;
  }
  return "TEXT";
}

namespace {

// The metavar of an option's value, from CLI11's type name ("INT:INT", "TEXT:{a,b}",
// "TEXT:DIR"): what it takes, without the tag.
std::string value_metavar(const CLI::Option* opt) {
  const std::string type = opt->get_type_name();
  const std::string base = type.substr(0, type.find(':'));
  if (type.find(":DIR") != std::string::npos) return "DIR";
  if (type.find(":FILE") != std::string::npos) return "FILE";
  if (type.find(":{") != std::string::npos) return "NAME";
  if (base == "INT" || base == "UINT") return "N";
  if (base == "FLOAT") return "X";
  return text_metavar(opt->get_single_name());
}

}  // namespace

std::string HelpFormatter::make_option_opts(const CLI::Option* opt) const {
  std::string out;
  if (!opt->get_option_text().empty()) {
    out = " " + opt->get_option_text();
  } else if (opt->get_type_size() != 0 && !opt->get_type_name().empty() && opt->nonpositional()) {
    out = " " + value_metavar(opt);
    if (opt->get_expected_max() >= CLI::detail::expected_max_vector_size) out += " ...";
  }
  if (opt->get_required()) out += " " + get_label("REQUIRED");
  return out;
}

std::string HelpFormatter::make_option_desc(const CLI::Option* opt) const {
  const std::string& description = opt->get_description();
  const std::string& shown = opt->get_default_str();
  if (shown.empty() || description.find("(default") != std::string::npos) return description;
  return description + " (default: " + shown + ")";
}

}  // namespace hnn::app
