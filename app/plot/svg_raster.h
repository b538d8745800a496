// SVG -> PNG in process, through librsvg and cairo (Debian's librsvg2-2, the
// library behind rsvg-convert): the PNG files of the run's figures.
//
// The libraries are opened at run time (dlopen), not linked: their C API is
// a handful of functions declared in svg_raster.cc, so the build needs no
// -dev packages of librsvg, cairo and GLib, and a machine without librsvg
// still runs (the figures keep their SVG and Vega spec; the note says what
// is missing). One rsvg-convert process per figure spent most of its time
// starting (loading its libraries, reading fontconfig's configuration) and
// compressing with zlib's default level; here the libraries load once per
// process and the PNG is compressed by libdeflate (OpenCV's writer at
// zlib's fastest level where libdeflate is missing).
#pragma once

#include <string>
#include <vector>

namespace rtscalib::app {

class SvgRasterizer {
 public:
  // The process's rasterizer (the libraries are opened at the first call).
  static const SvgRasterizer& Get();

  // "" when the libraries are there, else what is missing (for the note).
  const std::string& missing() const { return missing_; }

  // The SVG drawn on white at its own size in CSS pixels (96 per inch, as
  // rsvg-convert), as an 8-bit RGB PNG. False with *error (librsvg's or
  // cairo's message) when it cannot be drawn. Thread-safe.
  bool ToPng(const std::string& svg, std::vector<unsigned char>* png, std::string* error) const;

  // Draws a few letters, book and bold, and throws the PNG away. A
  // process's first text loads fontconfig's configuration and the fonts,
  // a thread's first text makes pango's font map of that thread: a
  // figure's PNG costs markedly more on a new thread, the first one of the
  // process more still. A thread that will draw figures warms up while it
  // waits for them.
  void WarmUp() const;

  struct Api;  // the functions found in the libraries (svg_raster.cc)

 private:
  SvgRasterizer();
  const Api* api_ = nullptr;
  std::string missing_;
};

}  // namespace rtscalib::app
