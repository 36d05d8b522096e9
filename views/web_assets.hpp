// The live page's static files (views/web/ and the vendored uPlot), compiled into the binary
// by cmake/embed_files.cmake so that the daemon serves them offline and from any directory.
#pragma once

#include <span>
#include <string_view>

namespace leakmon::views {

struct WebAsset {
  std::string_view path;  // URL path, e.g. "/" or "/uplot.min.js"
  std::string_view content_type;
  std::string_view body;
};

std::span<const WebAsset> web_assets();

}  // namespace leakmon::views
