#pragma once

// cwloc's readers take paths, libFuzzer hands bytes: a FuzzFile puts each input under a fixed
// name in this process's own temporary folder (in RAM under /dev/shm when there is one), and
// the folder goes when the process exits normally.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>

namespace cwloc::fuzz {

inline const std::filesystem::path& ProcessFolder() {
  static const struct Folder {
    std::filesystem::path path;
    Folder() {
      const std::filesystem::path shm = "/dev/shm";
      const std::filesystem::path base =
          std::filesystem::is_directory(shm) ? shm : std::filesystem::temp_directory_path();
      path = base / ("cwloc-fuzz-" + std::to_string(getpid()));
      std::filesystem::create_directories(path);
    }
    ~Folder() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  } folder;
  return folder.path;
}

// Writes `bytes` to `name` (which may contain a subfolder) and returns its path.
inline std::filesystem::path WriteFile(const std::string& name, std::span<const uint8_t> bytes) {
  const std::filesystem::path path = ProcessFolder() / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  return path;
}

inline std::filesystem::path WriteFile(const std::string& name, const uint8_t* data, size_t size) {
  return WriteFile(name, std::span<const uint8_t>(data, size));
}

}  // namespace cwloc::fuzz
