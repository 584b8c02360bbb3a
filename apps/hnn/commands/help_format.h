#pragma once
// --help without CLI11's type tags ("--steps INT:INT", "--seed UINT:UINT64"): an option shows a
// metavar for its value (its own option_text, else N for an integer, X for a number, NAME for
// one of a list, FILE, DIR or TEXT) and its default after its help as "(default: ...)".

#include <CLI/CLI.hpp>
#include <string>
#include <string_view>

namespace hnn::app {

/// A free-text option's metavar (the word --help shows for its value), by what the option (named
/// without dashes) takes: PATH, FILE, EXPR, COLUMN, NAMES, ... rather than CLI11's TEXT.
std::string text_metavar(std::string_view name);

class HelpFormatter : public CLI::Formatter {
 public:
  HelpFormatter() { column_width(28); }
  std::string make_option_opts(const CLI::Option* opt) const override;
  std::string make_option_desc(const CLI::Option* opt) const override;
};

}  // namespace hnn::app
