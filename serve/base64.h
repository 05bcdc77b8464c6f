#pragma once

// RFC 4648 base64: images in GeoPose requests, a session's options in its id.

#include <string>
#include <string_view>

namespace cwloc {

// Either alphabet (+/ or -_), padding optional, no line breaks; throws InputError naming `what`.
std::string DecodeBase64(std::string_view text, const std::string& what);

// The URL-safe alphabet (-_), no padding: a path segment as it is.
std::string EncodeBase64Url(std::string_view bytes);

}  // namespace cwloc
