#pragma once
// Shared by the speed-against-accuracy programs (scripts/charts.sh): a median-of-repetitions
// timer, a CSV writer, the noisy mass-spring data set and a quick HNN training on it.

#include <chrono>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "autodiff/autodiff.h"
#include "nn/nn.h"

namespace hnn::accuracy {

/// Seconds per call of a function: the median (and the extremes) over repeated samples.
struct Timing {
  double median = 0, min = 0, max = 0;
  int calls_per_sample = 0;
  int samples = 0;
};

struct TimingOptions {
  double min_sample_seconds = 0.02;  // each sample loops the call at least this long
  int samples = 7;                   // repetitions; the median is reported
  double slow_call_seconds = 0.5;    // calls longer than this get only `slow_samples` samples
  int slow_samples = 3;
};

/// Calls fn once to warm up (and to size the samples), then times the samples. A slow first
/// call counts as the first sample (its warm-up effects are negligible).
Timing time_call(const std::function<void()>& fn, const TimingOptions& options = {});

/// Times several functions in alternation (one sample of each per round, after a warm-up call
/// of each), so that a shared machine's changing load falls on all of them alike. Samples per
/// function as in time_call (the smallest count among them).
std::vector<Timing> time_interleaved(const std::vector<std::function<void()>>& fns,
                                     const TimingOptions& options = {});

/// A CSV file with a fixed header; rows are written as they come (so a crash keeps them).
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const std::string& header);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  void row(const std::string& line);

 private:
  std::FILE* file_;
};

/// The paper's mass-spring data: trajectories of H = q^2 + p^2 from radii U[0.1, 1], sampled at
/// `points` times in [0, 3], positions with N(0, noise^2) noise; targets are the exact dx/dt at
/// the noise-free states.
struct SpringData {
  nn::Matrix<double> x, dxdt;
};
SpringData spring_data(int trajectories, int points, double noise, std::uint64_t seed);

/// An HNN (2 -> hidden -> 1, tanh, orthogonal) trained on `data` by full-batch Adam (lr 1e-3)
/// for `steps` steps; final_loss receives the last training loss.
nn::Hnn<double> train_spring_hnn(const SpringData& data, const std::vector<nn::Index>& hidden,
                                 int steps, std::uint64_t seed, double* final_loss);

/// One chart of a chart program: its --only name, and what writes its CSV files into a folder
/// (`quick`: small sizes, for a smoke run).
struct Chart {
  std::string name;
  std::function<void(const std::string& out, bool quick)> write;
};

/// A chart program's main: parses --out DIR, --threads N, --quick and --only NAME (a chart's name
/// or all), refusing any other argument in one line, and writes the charts asked for. Returns the
/// exit code.
int run_charts(int argc, char** argv, const std::string& program, const std::vector<Chart>& charts);

}  // namespace hnn::accuracy
