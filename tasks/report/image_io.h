#pragma once
// Grayscale images for the pixel pendulum's figures: frames drawn onto a canvas, written as PNG
// (libpng's simplified API) and animated GIF (giflib), both atomically; and read back (tests).

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace hnn::tasks {

/// 8-bit grayscale, row-major, 0 = black.
struct GrayImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;

  GrayImage() = default;
  GrayImage(int w, int h, std::uint8_t fill = 0)
      : width(w), height(h), pixels(std::size_t(w) * std::size_t(h), fill) {}
  std::uint8_t& at(int x, int y) { return pixels[std::size_t(y) * std::size_t(width) + x]; }
  std::uint8_t at(int x, int y) const { return pixels[std::size_t(y) * std::size_t(width) + x]; }
};

/// Draws a square frame (side x side values, row-major) at (x0, y0), each value a scale x scale
/// block: v / max_value mapped to 0..255, clipped (decoded frames can leave [0, max]).
void draw_frame(GrayImage& canvas, int x0, int y0,
                const Eigen::Ref<const Eigen::RowVectorXf>& frame, int side, int scale,
                double max_value);

/// Writes an 8-bit grayscale PNG; throws std::runtime_error with libpng's message on failure.
void write_png(const std::filesystem::path& path, const GrayImage& image);
/// Writes an animated GIF with a gray palette that loops forever, `delay_cs` hundredths of a
/// second per frame. Every image must have the first one's size.
void write_gif(const std::filesystem::path& path, const std::vector<GrayImage>& images,
               int delay_cs);

/// A PNG read back as 8-bit gray (libpng converts colour); throws on a bad file.
GrayImage read_png(const std::filesystem::path& path);
/// Every image of a GIF, each as its palette's gray level (the red channel).
std::vector<GrayImage> read_gif(const std::filesystem::path& path);

}  // namespace hnn::tasks
