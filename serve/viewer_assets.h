#pragma once

// The viewer's files (serve/viewer/ and Debian's three.js), built into the binary so that
// cwloc-serve needs no files beside it and the page works offline.

#include <span>
#include <string_view>

namespace cwloc {

struct ViewerAsset {
  const char* path;  // where GET serves it: "/", "/viewer/viewer.js", ...
  const char* file;  // its name in serve/viewer/ (cwloc-serve --viewer-dir)
  const char* content_type;
  std::string_view bytes;
};

std::span<const ViewerAsset> ViewerAssets();

}  // namespace cwloc
