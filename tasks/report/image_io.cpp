// PNG and GIF files for the pixel pendulum's figures. Both are encoded in memory (libpng's
// simplified API, giflib's callback writer) and then written with write_file_atomic.

#include "tasks/report/image_io.h"

#include <fmt/format.h>
#include <gif_lib.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>

#include "nn/atomic_file.h"

namespace hnn::tasks {

namespace {

std::runtime_error image_error(const std::filesystem::path& path, const std::string& what) {
  return std::runtime_error(fmt::format("image '{}': {}", path.string(), what));
}

int append_bytes(GifFileType* gif, const GifByteType* bytes, int count) {
  static_cast<std::string*>(gif->UserData)
      ->append(reinterpret_cast<const char*>(bytes), std::size_t(count));
  return count;
}

struct GifReader {
  std::string bytes;
  std::size_t offset = 0;
};

int read_bytes(GifFileType* gif, GifByteType* out, int count) {
  auto* r = static_cast<GifReader*>(gif->UserData);
  const std::size_t n = std::min(std::size_t(count), r->bytes.size() - r->offset);
  std::memcpy(out, r->bytes.data() + r->offset, n);
  r->offset += n;
  return int(n);
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw image_error(path, "cannot open");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

void draw_frame(GrayImage& canvas, int x0, int y0,
                const Eigen::Ref<const Eigen::RowVectorXf>& frame, int side, int scale,
                double max_value) {
  for (int r = 0; r < side; ++r) {
    for (int c = 0; c < side; ++c) {
      const double v = std::clamp(double(frame(r * side + c)) / max_value, 0.0, 1.0);
      const auto level = std::uint8_t(std::lround(255.0 * v));
      for (int dy = 0; dy < scale; ++dy) {
        for (int dx = 0; dx < scale; ++dx) {
          const int x = x0 + c * scale + dx, y = y0 + r * scale + dy;
          if (x >= 0 && y >= 0 && x < canvas.width && y < canvas.height) canvas.at(x, y) = level;
        }
      }
    }
  }
}

void write_png(const std::filesystem::path& path, const GrayImage& image) {
  if (image.width <= 0 || image.height <= 0) throw image_error(path, "empty image");
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = png_uint_32(image.width);
  png.height = png_uint_32(image.height);
  png.format = PNG_FORMAT_GRAY;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&png, nullptr, &size, 0, image.pixels.data(), 0, nullptr)) {
    throw image_error(path, png.message);
  }
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&png, bytes.data(), &size, 0, image.pixels.data(), 0, nullptr)) {
    throw image_error(path, png.message);
  }
  bytes.resize(size);
  nn::write_file_atomic(path, bytes);
}

void write_gif(const std::filesystem::path& path, const std::vector<GrayImage>& images,
               int delay_cs) {
  if (images.empty()) throw image_error(path, "no frames");
  const int w = images[0].width, h = images[0].height;
  std::string bytes;
  int error = 0;
  GifFileType* gif = EGifOpen(&bytes, append_bytes, &error);
  if (gif == nullptr) throw image_error(path, GifErrorString(error));
  const auto fail = [&](const char* step) {
    const std::string message = GifErrorString(gif->Error) ? GifErrorString(gif->Error) : "?";
    EGifCloseFile(gif, &error);
    return image_error(path, fmt::format("{}: {}", step, message));
  };
  GifColorType colors[256];
  for (int i = 0; i < 256; ++i) colors[i] = {GifByteType(i), GifByteType(i), GifByteType(i)};
  const std::unique_ptr<ColorMapObject, void (*)(ColorMapObject*)> palette(
      GifMakeMapObject(256, colors), GifFreeMapObject);
  EGifSetGifVersion(gif, true);
  if (EGifPutScreenDesc(gif, w, h, 8, 0, palette.get()) == GIF_ERROR) throw fail("screen");
  // NETSCAPE2.0 application block: loop forever.
  const GifByteType loop[3] = {1, 0, 0};
  if (EGifPutExtensionLeader(gif, APPLICATION_EXT_FUNC_CODE) == GIF_ERROR ||
      EGifPutExtensionBlock(gif, 11, "NETSCAPE2.0") == GIF_ERROR ||
      EGifPutExtensionBlock(gif, 3, loop) == GIF_ERROR ||
      EGifPutExtensionTrailer(gif) == GIF_ERROR) {
    throw fail("loop extension");
  }
  GraphicsControlBlock gcb{};
  gcb.DisposalMode = DISPOSAL_UNSPECIFIED;
  gcb.DelayTime = delay_cs;
  gcb.TransparentColor = NO_TRANSPARENT_COLOR;
  GifByteType gcb_bytes[4];
  const auto gcb_size = int(EGifGCBToExtension(&gcb, gcb_bytes));
  for (const GrayImage& image : images) {
    if (image.width != w || image.height != h) {
      EGifCloseFile(gif, &error);
      throw image_error(path, "frames differ in size");
    }
    if (EGifPutExtension(gif, GRAPHICS_EXT_FUNC_CODE, gcb_size, gcb_bytes) == GIF_ERROR ||
        EGifPutImageDesc(gif, 0, 0, w, h, false, nullptr) == GIF_ERROR) {
      throw fail("image header");
    }
    std::vector<GifPixelType> line(static_cast<std::size_t>(w));
    for (int y = 0; y < h; ++y) {
      std::copy_n(image.pixels.begin() + std::ptrdiff_t(y) * w, w, line.begin());
      if (EGifPutLine(gif, line.data(), w) == GIF_ERROR) throw fail("pixels");
    }
  }
  if (EGifCloseFile(gif, &error) == GIF_ERROR) throw image_error(path, GifErrorString(error));
  nn::write_file_atomic(path, bytes);
}

GrayImage read_png(const std::filesystem::path& path) {
  const std::string bytes = read_file(path);
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&png, bytes.data(), bytes.size())) {
    throw image_error(path, png.message);
  }
  png.format = PNG_FORMAT_GRAY;
  GrayImage image(int(png.width), int(png.height));
  if (!png_image_finish_read(&png, nullptr, image.pixels.data(), 0, nullptr)) {
    throw image_error(path, png.message);
  }
  return image;
}

std::vector<GrayImage> read_gif(const std::filesystem::path& path) {
  GifReader reader{read_file(path)};
  int error = 0;
  GifFileType* gif = DGifOpen(&reader, read_bytes, &error);
  if (gif == nullptr) throw image_error(path, GifErrorString(error));
  if (DGifSlurp(gif) == GIF_ERROR) {
    const std::string message = GifErrorString(gif->Error);
    DGifCloseFile(gif, &error);
    throw image_error(path, message);
  }
  std::vector<GrayImage> images;
  for (int i = 0; i < gif->ImageCount; ++i) {
    const SavedImage& saved = gif->SavedImages[i];
    const ColorMapObject* map =
        saved.ImageDesc.ColorMap ? saved.ImageDesc.ColorMap : gif->SColorMap;
    GrayImage image(saved.ImageDesc.Width, saved.ImageDesc.Height);
    for (std::size_t k = 0; k < image.pixels.size(); ++k) {
      const int index = saved.RasterBits[k];
      image.pixels[k] = map && index < map->ColorCount ? map->Colors[index].Red : 0;
    }
    images.push_back(std::move(image));
  }
  DGifCloseFile(gif, &error);
  return images;
}

}  // namespace hnn::tasks
