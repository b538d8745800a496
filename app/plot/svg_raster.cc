#include "app/plot/svg_raster.h"

#include <dlfcn.h>

#include <cmath>
#include <cstdint>
#include <iterator>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rtscalib::app {

// librsvg 2.54's, cairo 1.16's and GLib's C API as far as it is used: opaque
// handles, a rectangle and GLib's error record, laid out as in their headers
// (rsvg.h, cairo.h, gerror.h).
struct SvgRasterizer::Api {
  struct Rectangle {
    double x, y, width, height;
  };
  struct Error {
    std::uint32_t domain;
    int code;
    char* message;
  };
  using Handle = void;
  using Surface = void;
  using Cairo = void;
  static constexpr int kFormatRgb24 = 1;  // CAIRO_FORMAT_RGB24: 32 bits per pixel, B G R x

  Handle* (*new_from_data)(const unsigned char*, std::size_t, Error**);
  int (*intrinsic_size)(Handle*, double*, double*);
  int (*render_document)(Handle*, Cairo*, const Rectangle*, Error**);
  void (*object_unref)(void*);
  void (*error_free)(Error*);
  Surface* (*image_surface_create)(int, int, int);
  int (*surface_status)(Surface*);
  Cairo* (*create)(Surface*);
  void (*set_source_rgb)(Cairo*, double, double, double);
  void (*paint)(Cairo*);
  void (*destroy)(Cairo*);
  void (*surface_flush)(Surface*);
  unsigned char* (*image_surface_get_data)(Surface*);
  int (*image_surface_get_stride)(Surface*);
  void (*surface_destroy)(Surface*);

  // libdeflate (Debian's libdeflate0, which OpenCV's TIFF reader brings):
  // optional, OpenCV's PNG writer when it is missing.
  using Compressor = void;
  Compressor* (*alloc_compressor)(int) = nullptr;
  std::size_t (*zlib_compress)(Compressor*, const void*, std::size_t, void*, std::size_t) = nullptr;
  std::size_t (*zlib_compress_bound)(Compressor*, std::size_t) = nullptr;
  void (*free_compressor)(Compressor*) = nullptr;
  std::uint32_t (*crc32)(std::uint32_t, const void*, std::size_t) = nullptr;
};

namespace {

// Resolves `name` in `lib` into *f; false (and *missing set) when absent.
template <typename F>
bool Find(void* lib, const char* name, F* f, std::string* missing) {
  *f = reinterpret_cast<F>(::dlsym(lib, name));
  if (*f == nullptr) *missing = std::string("librsvg/cairo without ") + name;
  return *f != nullptr;
}

// An 8-bit RGB PNG of cairo's RGB24 image (rows of B G R x) through
// libdeflate: no row filter, libdeflate's level 2. Both a figure's flat
// colours and a photo come out smaller than through OpenCV's writer (each
// row filtered with "Sub", zlib's fastest level), and sooner: libdeflate's
// matching is faster than zlib's at a level that finds more of it
// (BM_BenchFiguresPng times the figures' PNGs).
bool DeflatePng(const SvgRasterizer::Api& a, const unsigned char* bgrx, int stride, int width,
                int height, std::vector<unsigned char>* png) {
  // The buffers and the compressor stay with the thread for its next
  // figure: fresh ones of a few megabytes cost a page fault per 4 kB.
  thread_local std::vector<unsigned char> raw, idat;
  thread_local std::unique_ptr<void, void (*)(void*)> compressor(nullptr, [](void*) {});
  const std::size_t row = 1 + 3 * static_cast<std::size_t>(width);
  raw.resize(row * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    const unsigned char* in = bgrx + static_cast<std::size_t>(y) * stride;
    unsigned char* out = raw.data() + static_cast<std::size_t>(y) * row;
    *out++ = 0;  // filter type None
    for (int x = 0; x < width; ++x, in += 4) {
      *out++ = in[2];
      *out++ = in[1];
      *out++ = in[0];
    }
  }
  if (compressor == nullptr) {
    compressor = std::unique_ptr<void, void (*)(void*)>(a.alloc_compressor(2), a.free_compressor);
  }
  if (compressor == nullptr) return false;
  idat.resize(a.zlib_compress_bound(compressor.get(), raw.size()));
  const std::size_t n =
      a.zlib_compress(compressor.get(), raw.data(), raw.size(), idat.data(), idat.size());
  if (n == 0) return false;
  png->clear();
  png->reserve(n + 64);
  const unsigned char signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  png->insert(png->end(), std::begin(signature), std::end(signature));
  auto be32 = [&](std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8)
      png->push_back(static_cast<unsigned char>(v >> shift));
  };
  // A chunk: its length, type and data, and the CRC of type and data.
  auto chunk = [&](const char* type, const unsigned char* data, std::size_t size) {
    be32(static_cast<std::uint32_t>(size));
    const std::size_t at = png->size();
    png->insert(png->end(), type, type + 4);
    png->insert(png->end(), data, data + size);
    be32(a.crc32(0, png->data() + at, size + 4));
  };
  unsigned char ihdr[13];
  for (int k = 0; k < 4; ++k) {
    ihdr[k] = static_cast<unsigned char>(static_cast<std::uint32_t>(width) >> (24 - 8 * k));
    ihdr[4 + k] = static_cast<unsigned char>(static_cast<std::uint32_t>(height) >> (24 - 8 * k));
  }
  ihdr[8] = 8;   // bits per sample
  ihdr[9] = 2;   // colour type: RGB
  ihdr[10] = 0;  // deflate
  ihdr[11] = 0;  // adaptive filtering (each row's filter byte)
  ihdr[12] = 0;  // not interlaced
  chunk("IHDR", ihdr, sizeof ihdr);
  chunk("IDAT", idat.data(), n);
  chunk("IEND", nullptr, 0);
  return true;
}

}  // namespace

const SvgRasterizer& SvgRasterizer::Get() {
  static const SvgRasterizer rasterizer;  // thread-safe initialisation
  return rasterizer;
}

SvgRasterizer::SvgRasterizer() {
  // Never closed: the libraries keep process-wide state (GObject's type
  // system, fontconfig's configuration) that must not be unloaded.
  void* rsvg = ::dlopen("librsvg-2.so.2", RTLD_NOW | RTLD_LOCAL);
  void* cairo = ::dlopen("libcairo.so.2", RTLD_NOW | RTLD_LOCAL);
  void* gobject = ::dlopen("libgobject-2.0.so.0", RTLD_NOW | RTLD_LOCAL);
  void* glib = ::dlopen("libglib-2.0.so.0", RTLD_NOW | RTLD_LOCAL);
  if (rsvg == nullptr || cairo == nullptr || gobject == nullptr || glib == nullptr) {
    missing_ = "librsvg is not installed (Debian package librsvg2-2)";
    return;
  }
  static Api api;
  // rsvg_handle_get_intrinsic_size_in_pixels is librsvg 2.52's (Debian 12
  // has 2.54); an older librsvg is reported as missing it.
  const bool found =
      Find(rsvg, "rsvg_handle_new_from_data", &api.new_from_data, &missing_) &&
      Find(rsvg, "rsvg_handle_get_intrinsic_size_in_pixels", &api.intrinsic_size, &missing_) &&
      Find(rsvg, "rsvg_handle_render_document", &api.render_document, &missing_) &&
      Find(gobject, "g_object_unref", &api.object_unref, &missing_) &&
      Find(glib, "g_error_free", &api.error_free, &missing_) &&
      Find(cairo, "cairo_image_surface_create", &api.image_surface_create, &missing_) &&
      Find(cairo, "cairo_surface_status", &api.surface_status, &missing_) &&
      Find(cairo, "cairo_create", &api.create, &missing_) &&
      Find(cairo, "cairo_set_source_rgb", &api.set_source_rgb, &missing_) &&
      Find(cairo, "cairo_paint", &api.paint, &missing_) &&
      Find(cairo, "cairo_destroy", &api.destroy, &missing_) &&
      Find(cairo, "cairo_surface_flush", &api.surface_flush, &missing_) &&
      Find(cairo, "cairo_image_surface_get_data", &api.image_surface_get_data, &missing_) &&
      Find(cairo, "cairo_image_surface_get_stride", &api.image_surface_get_stride, &missing_) &&
      Find(cairo, "cairo_surface_destroy", &api.surface_destroy, &missing_);
  if (found) api_ = &api;
  if (void* deflate = ::dlopen("libdeflate.so.0", RTLD_NOW | RTLD_LOCAL)) {
    std::string absent;
    Api d = api;
    if (Find(deflate, "libdeflate_alloc_compressor", &d.alloc_compressor, &absent) &&
        Find(deflate, "libdeflate_zlib_compress", &d.zlib_compress, &absent) &&
        Find(deflate, "libdeflate_zlib_compress_bound", &d.zlib_compress_bound, &absent) &&
        Find(deflate, "libdeflate_free_compressor", &d.free_compressor, &absent) &&
        Find(deflate, "libdeflate_crc32", &d.crc32, &absent)) {
      api = d;
    }
  }
}

void SvgRasterizer::WarmUp() const {
  static const std::string kLetters =
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"40\" height=\"20\">"
      "<text x=\"1\" y=\"9\" font-family=\"sans-serif\" font-size=\"10\">Ag</text>"
      "<text x=\"1\" y=\"19\" font-family=\"sans-serif\" font-size=\"10\" "
      "font-weight=\"bold\">Ag</text></svg>";
  std::vector<unsigned char> png;
  std::string error;
  ToPng(kLetters, &png, &error);
}

bool SvgRasterizer::ToPng(const std::string& svg, std::vector<unsigned char>* png,
                          std::string* error) const {
  if (api_ == nullptr) {
    *error = missing_;
    return false;
  }
  const Api& a = *api_;
  auto take = [&](Api::Error* e, const char* what) {
    *error = std::string(what) + (e != nullptr && e->message ? std::string(": ") + e->message : "");
    if (e != nullptr) a.error_free(e);
    return false;
  };
  Api::Error* e = nullptr;
  Api::Handle* handle =
      a.new_from_data(reinterpret_cast<const unsigned char*>(svg.data()), svg.size(), &e);
  if (handle == nullptr) return take(e, "librsvg cannot read the SVG");
  struct Owned {
    const Api& a;
    Api::Handle* handle;
    Api::Surface* surface = nullptr;
    Api::Cairo* cr = nullptr;
    ~Owned() {
      if (cr) a.destroy(cr);
      if (surface) a.surface_destroy(surface);
      a.object_unref(handle);
    }
  } owned{a, handle};
  double w = 0, h = 0;
  if (!a.intrinsic_size(handle, &w, &h) || !(w > 0 && h > 0) || !(w < 32768 && h < 32768)) {
    *error = "the SVG has no usable size in pixels";
    return false;
  }
  // rsvg-convert's rule: a fractional size is rounded up.
  const int width = static_cast<int>(std::ceil(w)), height = static_cast<int>(std::ceil(h));
  owned.surface = a.image_surface_create(Api::kFormatRgb24, width, height);
  if (a.surface_status(owned.surface) != 0) {
    *error =
        "cairo cannot make a " + std::to_string(width) + " x " + std::to_string(height) + " image";
    return false;
  }
  owned.cr = a.create(owned.surface);
  a.set_source_rgb(owned.cr, 1, 1, 1);  // rsvg-convert --background-color=white
  a.paint(owned.cr);
  const Api::Rectangle viewport{0, 0, static_cast<double>(width), static_cast<double>(height)};
  if (!a.render_document(handle, owned.cr, &viewport, &e)) return take(e, "librsvg failed");
  a.surface_flush(owned.surface);
  if (a.crc32 != nullptr &&
      DeflatePng(a, a.image_surface_get_data(owned.surface),
                 a.image_surface_get_stride(owned.surface), width, height, png)) {
    return true;
  }
  const cv::Mat bgrx(height, width, CV_8UC4, a.image_surface_get_data(owned.surface),
                     static_cast<size_t>(a.image_surface_get_stride(owned.surface)));
  cv::Mat bgr;
  cv::cvtColor(bgrx, bgr, cv::COLOR_BGRA2BGR);
  // OpenCV's fast PNG path (no compression level given: every row filtered
  // with "Sub", zlib's fastest level) with zlib's default matching instead of
  // OpenCV's run-length only: a figure's flat colours repeat in long
  // matches that run-length misses, so the files are markedly smaller at
  // about the same time, while an explicit level makes libpng choose each
  // row's filter, which costs most of the time and saves few bytes
  // (BM_PhotoPng in photo_session_benchmark times both paths on photos).
  if (!cv::imencode(".png", bgr, *png,
                    {cv::IMWRITE_PNG_STRATEGY, cv::IMWRITE_PNG_STRATEGY_DEFAULT})) {
    *error = "OpenCV cannot encode the PNG";
    return false;
  }
  return true;
}

}  // namespace rtscalib::app
