#pragma once

// A request as the handlers see it, once the HTTP layer (http_server.h) has read it whole, and
// the response they make: plain values, no socket.

#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace cwloc {

// A part of a multipart/form-data body (RFC 7578), borrowed from the request's body.
struct FormPart {
  std::string name;
  std::string filename;      // empty without one
  std::string content_type;  // empty without one
  std::string_view content;
};

// Splits a multipart/form-data body on the boundary its Content-Type names; throws InputError
// "multipart body: ..." naming what is malformed. A part without a name is refused; the first
// of two parts with one name is kept.
std::vector<FormPart> ParseMultipart(std::string_view content_type, std::string_view body);

// Decodes %XX and '+' of a URL's query; nullopt for a malformed escape.
std::optional<std::string> DecodeUrlComponent(std::string_view text);

struct HttpRequest {
  std::string method;                         // "GET", "POST", ...
  std::string path;                           // the target before '?', decoded
  std::map<std::string, std::string> params;  // the query's, decoded; the first of a repeated one
  std::vector<std::pair<std::string, std::string>> headers;  // as received, names lower-cased
  std::string body;
  std::vector<FormPart> parts;       // a multipart/form-data body's, parsed before the handler runs
  std::vector<std::string> matches;  // the route's captures (a session's id)

  // The first header of that name (lower case), or "".
  std::string Header(std::string_view name) const;
  std::string Param(const std::string& name) const;
  bool IsMultipart() const;
  const FormPart* Part(std::string_view name) const;
};

struct HttpResponse;

// A handler's answer that waits for a query worker: `work` runs there (work_queue.h) unless no
// worker starts it by `start_by`, and fills the response; the HTTP layer writes the response
// when it is done, holding no thread for the connection meanwhile.
struct DeferredWork {
  std::function<void(HttpResponse&)> work;
  bool photo = false;  // a photo's query or features' (ServiceTimes keeps their times apart)
  std::chrono::steady_clock::time_point deadline;
};

struct HttpResponse {
  int status = 200;
  std::vector<std::pair<std::string, std::string>> headers;
  std::string body;
  std::string content_type = "text/plain";
  bool close = false;  // end the connection after this response
  std::optional<DeferredWork> deferred;

  void SetContent(std::string content, std::string type) {
    body = std::move(content);
    content_type = std::move(type);
  }
  void SetHeader(std::string name, std::string value);
};

}  // namespace cwloc
