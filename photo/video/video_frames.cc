#include "photo/video/video_frames.h"

#include <dlfcn.h>

#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace cwloc {
namespace {

constexpr char kModule[] = "libcwloc_video_ffmpeg.so";

// The module's entry point, loaded once: from the lib/ folder beside the program's folder (the
// build tree's bin/ and tests/, an install's bin/ with CWLOC_VIDEO_MODULE_FROM_BIN), else where
// dlopen looks for libraries. It stays loaded: its code throws and its frames are in use.
OpenVideoFunction OpenVideo() {
  static OpenVideoFunction open = nullptr;
  static std::string failure;
  static std::once_flag once;
  std::call_once(once, [] {
    std::error_code error;
    const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
    std::vector<std::string> candidates;
    if (!error) {
      for (const char* from_bin : {"../lib", CWLOC_VIDEO_MODULE_FROM_BIN}) {
        const std::string path = (program.parent_path() / from_bin / kModule).lexically_normal();
        if (candidates.empty() || candidates.back() != path) candidates.push_back(path);
      }
    }
    candidates.push_back(kModule);
    for (const std::string& candidate : candidates) {
      void* module = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (module == nullptr) {
        failure += "\n  " + std::string(dlerror());
        continue;
      }
      open = reinterpret_cast<OpenVideoFunction>(dlsym(module, kOpenVideoSymbol));
      if (open != nullptr) return;
      failure += "\n  " + candidate + ": no " + kOpenVideoSymbol;
    }
  });
  if (open == nullptr)
    throw std::runtime_error(std::string("cannot load FFmpeg's video module ") + kModule + ":" +
                             failure);
  return open;
}

}  // namespace

VideoFrames::VideoFrames(const std::filesystem::path& path, uint64_t max_pixels)
    : decoder_(OpenVideo()(path.c_str(), max_pixels)) {}

VideoFrames::~VideoFrames() = default;

}  // namespace cwloc
