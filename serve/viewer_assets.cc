#include "serve/viewer_assets.h"

// viewer_assets.S's symbols: each file's first byte, and the byte after its last.
extern "C" {
#define CWLOC_VIEWER_FILE(symbol) extern const char symbol[], symbol##_end[];
CWLOC_VIEWER_FILE(cwloc_viewer_index_html)
CWLOC_VIEWER_FILE(cwloc_viewer_viewer_js)
CWLOC_VIEWER_FILE(cwloc_viewer_geometry_js)
CWLOC_VIEWER_FILE(cwloc_viewer_three_js)
CWLOC_VIEWER_FILE(cwloc_viewer_orbit_controls_js)
#undef CWLOC_VIEWER_FILE
}

namespace cwloc {
namespace {

std::string_view Bytes(const char* begin, const char* end) {
  return std::string_view(begin, static_cast<size_t>(end - begin));
}

}  // namespace

std::span<const ViewerAsset> ViewerAssets() {
  static const ViewerAsset kAssets[] = {
      {"/", "index.html", "text/html; charset=utf-8",
       Bytes(cwloc_viewer_index_html, cwloc_viewer_index_html_end)},
      {"/viewer/viewer.js", "viewer.js", "text/javascript",
       Bytes(cwloc_viewer_viewer_js, cwloc_viewer_viewer_js_end)},
      {"/viewer/geometry.js", "geometry.js", "text/javascript",
       Bytes(cwloc_viewer_geometry_js, cwloc_viewer_geometry_js_end)},
      {"/viewer/three.min.js", "three.min.js", "text/javascript",
       Bytes(cwloc_viewer_three_js, cwloc_viewer_three_js_end)},
      {"/viewer/OrbitControls.js", "OrbitControls.js", "text/javascript",
       Bytes(cwloc_viewer_orbit_controls_js, cwloc_viewer_orbit_controls_js_end)},
  };
  return kAssets;
}

}  // namespace cwloc
