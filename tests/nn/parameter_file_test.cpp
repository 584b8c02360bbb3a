// Parameter files: bit-exact round trips, atomic writes, and clear refusals of misfits.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "nn_test_util.h"

namespace ad = hnn::ad;
namespace nn = hnn::nn;
namespace fs = std::filesystem;
using MatrixD = nn::Matrix<double>;
using nn::ModelKind;
using nn::testing::small_config;

namespace {

class ParameterFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("hnn_nn_parameter_file_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path file(const std::string& name) const { return dir_ / name; }
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

// Runs f, which must throw ParameterFileError naming `path` with `reason` in its message.
template <typename F>
void expect_refusal(F f, const fs::path& path, const std::string& reason) {
  try {
    f();
    ADD_FAILURE() << "no error; expected '" << reason << "'";
  } catch (const nn::ParameterFileError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find(reason), std::string::npos) << what;
    EXPECT_EQ(e.path(), path);
  }
}

template <typename T>
std::vector<nn::Matrix<T>> values_of(const nn::Module<T>& m) {
  std::vector<nn::Matrix<T>> values;
  for (const auto& p : m.parameters()) values.push_back(p.value());
  return values;
}

TEST_F(ParameterFile, SaveThenLoadReproducesPredictionsBitForBit) {
  std::mt19937_64 rng(1), other(2);
  const MatrixD x = nn::random_normal<double>(16, 2, rng);
  for (const ModelKind kind : {ModelKind::kHnn, ModelKind::kBaseline}) {
    const auto model = nn::make_model<double>(small_config(kind, 2, {16, 16}), rng);
    const auto fresh = nn::make_model<double>(small_config(kind, 2, {16, 16}), other);
    ASSERT_NE(fresh->field(x), model->field(x));
    nn::save_parameters(file("model.bin"), *model);
    nn::load_parameters(file("model.bin"), *fresh);
    EXPECT_EQ(fresh->field(x), model->field(x));
    EXPECT_EQ(values_of(*fresh), values_of(*model));
  }
  // float too, and an overwrite of the same path.
  const auto model_f = nn::make_model<float>(small_config(ModelKind::kHnn, 2, {8}), rng);
  const auto fresh_f = nn::make_model<float>(small_config(ModelKind::kHnn, 2, {8}), other);
  nn::save_parameters(file("model.bin"), *model_f);
  nn::load_parameters(file("model.bin"), *fresh_f);
  EXPECT_EQ(fresh_f->field(x.cast<float>()), model_f->field(x.cast<float>()));
  // The temporary file was renamed into place: nothing else is left behind.
  EXPECT_EQ(listing(), std::vector<std::string>{"model.bin"});
}

TEST_F(ParameterFile, InfoDescribesTheFile) {
  std::mt19937_64 rng(3);
  const nn::Hnn<double> hnn(small_config(ModelKind::kHnn, 4, {8, 8}), rng);
  nn::save_parameters(file("hnn.bin"), hnn);
  const nn::ParameterFileInfo info = nn::read_parameter_file_info(file("hnn.bin"));
  EXPECT_EQ(info.version, nn::kParameterFileVersion);
  EXPECT_EQ(info.scalar, nn::ScalarType::kFloat64);
  EXPECT_EQ(info.kind, "hnn:tanh");
  ASSERT_EQ(info.entries.size(), 5u);
  EXPECT_EQ(info.entries[0].name, "mlp.layers.0.weight");
  EXPECT_EQ(info.entries[0].rows, 4);
  EXPECT_EQ(info.entries[0].cols, 8);
  EXPECT_EQ(info.entries[4].name, "mlp.layers.2.weight");
  EXPECT_EQ(info.entries[4].cols, 1);
}

TEST_F(ParameterFile, RefusesAMismatchedModelAndLeavesItUnchanged) {
  std::mt19937_64 rng(4);
  const nn::Hnn<double> saved(small_config(ModelKind::kHnn, 2, {8, 8}), rng);
  nn::save_parameters(file("hnn.bin"), saved);
  const fs::path path = file("hnn.bin");

  nn::Hnn<double> wider(small_config(ModelKind::kHnn, 2, {8, 9}), rng);
  const auto before = values_of(wider);
  expect_refusal([&] { nn::load_parameters(path, wider); }, path,
                 "parameter 'mlp.layers.1.weight' is 8x8 in the file but 8x9 in the model");
  EXPECT_EQ(values_of(wider), before);  // never half-loaded: layer 0 matched but was not set

  nn::Hnn<double> deeper(small_config(ModelKind::kHnn, 2, {8, 8, 8}), rng);
  expect_refusal([&] { nn::load_parameters(path, deeper); }, path,
                 "parameter 'mlp.layers.2.weight' is 8x1 in the file but 8x8 in the model");
  nn::Hnn<double> shallower(small_config(ModelKind::kHnn, 2, {8}), rng);
  expect_refusal([&] { nn::load_parameters(path, shallower); }, path, "8x1 in the model");

  nn::Hnn<double> relu(
      small_config(ModelKind::kHnn, 2, {8, 8}, nn::FieldType::kSolenoidal, nn::Activation::kRelu),
      rng);
  expect_refusal([&] { nn::load_parameters(path, relu); }, path,
                 "holds a 'hnn:tanh' model but the model is 'hnn:relu'");
  nn::Baseline<double> baseline(small_config(ModelKind::kBaseline, 2, {8, 8}), rng);
  expect_refusal([&] { nn::load_parameters(path, baseline); }, path, "'baseline:tanh'");
  // Names: a parameter missing from the file, or one the model lacks.
  const nn::Mlp<double> no_bias({{2, 4, 1}}, rng);
  nn::Mlp<double> with_bias({{2, 4, 1}, nn::Activation::kTanh, nn::Init::kOrthogonal, true}, rng);
  nn::save_parameters(file("mlp.bin"), no_bias);
  expect_refusal([&] { nn::load_parameters(file("mlp.bin"), with_bias); }, file("mlp.bin"),
                 "has no parameter 'layers.1.bias'");
  nn::save_parameters(file("mlp.bin"), with_bias);
  nn::Mlp<double> target({{2, 4, 1}}, rng);
  expect_refusal([&] { nn::load_parameters(file("mlp.bin"), target); }, file("mlp.bin"),
                 "has parameter 'layers.1.bias' that the model lacks");
  nn::Hnn<float> as_float(small_config(ModelKind::kHnn, 2, {8, 8}), rng);
  expect_refusal([&] { nn::load_parameters(path, as_float); }, path,
                 "holds float64 parameters but the model is float32");
}

TEST_F(ParameterFile, RefusesTruncatedCorruptAndForeignFiles) {
  std::mt19937_64 rng(5);
  nn::Hnn<double> model(small_config(ModelKind::kHnn, 2, {8}), rng);
  nn::save_parameters(file("good.bin"), model);
  const std::string good = read_bytes(file("good.bin"));
  const auto before = values_of(model);
  const fs::path bad = file("bad.bin");
  // Cut in the header, in a name, in the values and before the checksum.
  for (const std::size_t size : {std::size_t(0), std::size_t(5), std::size_t(14), std::size_t(40),
                                 good.size() / 2, good.size() - 8, good.size() - 1}) {
    write_bytes(bad, good.substr(0, size));
    const std::string reason = size < 8 ? "not an hnn parameter file" : "truncated";
    expect_refusal([&] { nn::load_parameters(bad, model); }, bad, reason);
    EXPECT_EQ(values_of(model), before) << "cut at " << size;
  }
  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  write_bytes(bad, flipped);
  expect_refusal([&] { nn::load_parameters(bad, model); }, bad, "checksum");
  write_bytes(bad, good + "x");
  expect_refusal([&] { nn::load_parameters(bad, model); }, bad, "unexpected bytes");
  std::string newer = good;
  newer[8] = 2;
  write_bytes(bad, newer);
  expect_refusal([&] { nn::load_parameters(bad, model); }, bad,
                 "format version 2, but this build reads version 1");
  // A corrupt shape is refused before anything is allocated for it.
  std::string huge = good;
  const std::size_t shape_at = huge.find("mlp.layers.0.weight") + 19;
  for (int b = 0; b < 8; ++b) huge[shape_at + b] = 0;            // rows = 0
  for (int b = 8; b < 16; ++b) huge[shape_at + b] = char(0xff);  // cols = 2^64 - 1
  write_bytes(bad, huge);
  expect_refusal([&] { nn::load_parameters(bad, model); }, bad,
                 "corrupt: parameter 'mlp.layers.0.weight' is 0x18446744073709551615");
  for (int b = 0; b < 16; ++b) huge[shape_at + b] = b == 3 || b == 11 ? 1 : 0;  // 2^24 x 2^24
  write_bytes(bad, huge);
  expect_refusal([&] { nn::load_parameters(bad, model); }, bad, "truncated");
  expect_refusal([&] { nn::load_parameters(dir_, model); }, dir_, "is a directory");
  write_bytes(bad, "step,loss\n0,0.5\n1,0.25\n");
  expect_refusal([&] { nn::load_parameters(bad, model); }, bad, "not an hnn parameter file");
  expect_refusal([&] { nn::load_parameters(file("missing.bin"), model); }, file("missing.bin"),
                 "cannot open");
  EXPECT_EQ(values_of(model), before);
}

TEST_F(ParameterFile, FailedSaveLeavesNoTemporaryFile) {
  std::mt19937_64 rng(6);
  const nn::Baseline<double> model(small_config(ModelKind::kBaseline, 2, {4}), rng);
  const fs::path nowhere = file("no/such/dir/model.bin");
  expect_refusal([&] { nn::save_parameters(nowhere, model); }, nowhere, "does not exist");
  EXPECT_TRUE(listing().empty());
}

TEST_F(ParameterFile, SavesSeveralModulesTogether) {
  // The pixel task saves an autoencoder and an HNN in one file, by explicit names and kind.
  std::mt19937_64 rng(7), other(8);
  nn::AutoencoderConfig config;
  config.input_dim = 6;
  config.hidden_dim = 4;
  const nn::Autoencoder<float> ae(config, rng), ae2(config, other);
  const nn::Hnn<float> hnn(small_config(ModelKind::kHnn, 2, {4}), rng);
  const nn::Hnn<float> hnn2(small_config(ModelKind::kHnn, 2, {4}), other);
  const auto joined = [](const nn::Autoencoder<float>& a, const nn::Hnn<float>& h) {
    auto all = a.named_parameters();
    for (auto p : h.named_parameters()) all.push_back({"hnn." + p.name, p.var});
    return all;
  };
  nn::save_parameters<float>(file("pixel.bin"), "pixel-hnn", joined(ae, hnn));
  nn::load_parameters<float>(file("pixel.bin"), "pixel-hnn", joined(ae2, hnn2));
  EXPECT_EQ(values_of(ae2), values_of(ae));
  EXPECT_EQ(values_of(hnn2), values_of(hnn));
  auto duplicated = joined(ae, hnn);
  duplicated.push_back(duplicated.front());
  expect_refusal([&] { nn::save_parameters<float>(file("dup.bin"), "x", duplicated); },
                 file("dup.bin"), "duplicate parameter name 'encoder.0.weight'");
}

}  // namespace
