// Text inside HTML and SVG (report.html, the figures' SVG files): the
// characters that markup reads as its own escaped.
#pragma once

#include <string>

namespace rtscalib::app {

// `s` with & < > " written as entities: safe as element text and inside a
// double-quoted attribute.
std::string EscapeMarkup(const std::string& s);

}  // namespace rtscalib::app
