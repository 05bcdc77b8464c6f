#include "serve/http_message.h"

#include <algorithm>
#include <cctype>

#include "base/error.h"

namespace cwloc {
namespace {

std::string Lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

std::string_view Trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

// A header parameter's value (`name=value` or `name="value"`) of a header such as
// `form-data; name="image"; filename="a.jpg"`, or nullopt.
std::optional<std::string> HeaderParameter(std::string_view header, std::string_view name) {
  size_t at = 0;
  while ((at = header.find(';', at)) != std::string_view::npos) {
    std::string_view rest = Trim(header.substr(at + 1));
    at += 1;
    const size_t equals = rest.find('=');
    if (equals == std::string_view::npos || Lower(Trim(rest.substr(0, equals))) != name) continue;
    rest = Trim(rest.substr(equals + 1));
    if (!rest.empty() && rest.front() == '"') {
      const size_t close = rest.find('"', 1);
      if (close == std::string_view::npos) return std::nullopt;
      return std::string(rest.substr(1, close - 1));
    }
    return std::string(rest.substr(0, rest.find(';')));
  }
  return std::nullopt;
}

// A part's header block into `part`; throws for a malformed one.
void ParsePartHeaders(std::string_view block, FormPart* part) {
  bool disposition = false;
  while (!block.empty()) {
    const size_t end = block.find("\r\n");
    const std::string_view line = block.substr(0, end);
    block.remove_prefix(end == std::string_view::npos ? block.size() : end + 2);
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos)
      throw InputError("multipart body: a part's header has no ':'");
    const std::string name = Lower(Trim(line.substr(0, colon)));
    const std::string_view value = Trim(line.substr(colon + 1));
    if (name == "content-disposition") {
      disposition = true;
      part->name = HeaderParameter(value, "name").value_or("");
      part->filename = HeaderParameter(value, "filename").value_or("");
    } else if (name == "content-type") {
      part->content_type = std::string(value);
    }
  }
  if (!disposition || part->name.empty())
    throw InputError("multipart body: a part without Content-Disposition's name");
}

}  // namespace

std::vector<FormPart> ParseMultipart(std::string_view content_type, std::string_view body) {
  const std::optional<std::string> boundary = HeaderParameter(content_type, "boundary");
  if (!boundary || boundary->empty() || boundary->size() > 200)
    throw InputError("multipart body: no boundary in its Content-Type");
  const std::string delimiter = "--" + *boundary;
  // The first delimiter may follow a preamble; every later one follows a CRLF.
  size_t at = body.substr(0, delimiter.size()) == delimiter ? 0 : body.find("\r\n" + delimiter);
  if (at == std::string_view::npos) throw InputError("multipart body: no boundary line");
  at += at == 0 ? delimiter.size() : delimiter.size() + 2;
  std::vector<FormPart> parts;
  const std::string next_delimiter = "\r\n" + delimiter;
  while (true) {
    if (body.substr(at, 2) == "--") return parts;  // the closing delimiter
    if (body.substr(at, 2) != "\r\n")
      throw InputError("multipart body: a boundary line ends badly");
    at += 2;
    const size_t headers_end = body.find("\r\n\r\n", at);
    const size_t content_end = body.find(next_delimiter, at);
    if (content_end == std::string_view::npos)
      throw InputError("multipart body: a part has no closing boundary");
    FormPart part;
    if (headers_end == std::string_view::npos || headers_end > content_end)
      throw InputError("multipart body: a part's headers do not end");
    ParsePartHeaders(body.substr(at, headers_end - at), &part);
    part.content = body.substr(headers_end + 4, content_end - headers_end - 4);
    const bool seen = std::any_of(parts.begin(), parts.end(),
                                  [&](const FormPart& p) { return p.name == part.name; });
    if (!seen) parts.push_back(std::move(part));
    at = content_end + next_delimiter.size();
  }
}

std::optional<std::string> DecodeUrlComponent(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '+') {
      out += ' ';
    } else if (text[i] == '%') {
      const auto hex = [](char c) -> int {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
      };
      if (i + 2 >= text.size()) return std::nullopt;
      const int high = hex(text[i + 1]), low = hex(text[i + 2]);
      if (high < 0 || low < 0) return std::nullopt;
      out += static_cast<char>(high * 16 + low);
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

std::string HttpRequest::Header(std::string_view name) const {
  for (const auto& [key, value] : headers)
    if (key == name) return value;
  return "";
}

std::string HttpRequest::Param(const std::string& name) const {
  const auto found = params.find(name);
  return found == params.end() ? "" : found->second;
}

bool HttpRequest::IsMultipart() const {
  return Lower(Header("content-type")).rfind("multipart/form-data", 0) == 0;
}

const FormPart* HttpRequest::Part(std::string_view name) const {
  for (const FormPart& part : parts)
    if (part.name == name) return &part;
  return nullptr;
}

void HttpResponse::SetHeader(std::string name, std::string value) {
  for (auto& [key, old] : headers) {
    if (Lower(key) == Lower(name)) {
      old = std::move(value);
      return;
    }
  }
  headers.emplace_back(std::move(name), std::move(value));
}

}  // namespace cwloc
