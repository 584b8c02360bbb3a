#pragma once
// The one error type of tasks/: a run cannot go as asked (bad option, bad data, a file that is
// not what it should be). Its message says what and where, and what to do when that is known.

#include <fmt/format.h>

#include <stdexcept>

namespace hnn::tasks {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace hnn::tasks

/// Throws tasks::Error with the fmt-formatted message unless `cond` holds.
#define HNN_TASKS_CHECK(cond, ...)                                    \
  do {                                                                \
    if (!(cond)) throw ::hnn::tasks::Error(fmt::format(__VA_ARGS__)); \
  } while (false)
