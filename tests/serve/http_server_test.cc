// cwloc-serve's HTTP layer (serve/http_server.h) against raw sockets, as a hostile or slow
// client meets it on an open port: a body announced over the limit is refused before it is
// sent, headers and bodies that stall are answered 408, a connection beyond the limit 503 at
// once, and the ordinary cases (keep-alive, 100-continue, deferred work, stop) work.
#include "serve/http_server.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "base/error.h"

namespace cwloc {
namespace {

using Clock = std::chrono::steady_clock;

// A client socket; reads give up after 10 s (a server that never answers fails the test).
class RawClient {
 public:
  explicit RawClient(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    timeval timeout{10, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
  }
  ~RawClient() { ::close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;

  bool connected() const { return connected_; }
  bool Send(const std::string& bytes) {
    size_t sent = 0;
    while (sent < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) return false;
      sent += static_cast<size_t>(n);
    }
    return true;
  }

  struct Response {
    int status = 0;  // 0: none read
    std::string head, body;
  };
  // One response: its head, then Content-Length bytes of body.
  Response Read() {
    Response response;
    size_t end;
    while ((end = buffer_.find("\r\n\r\n")) == std::string::npos)
      if (!Fill()) return response;
    response.head = buffer_.substr(0, end + 4);
    buffer_.erase(0, end + 4);
    response.status = std::stoi(response.head.substr(9, 3));
    const size_t length_at = Lower(response.head).find("content-length: ");
    const size_t length =
        length_at == std::string::npos ? 0 : std::stoul(response.head.substr(length_at + 16));
    while (buffer_.size() < length)
      if (!Fill()) return response;
    response.body = buffer_.substr(0, length);
    buffer_.erase(0, length);
    return response;
  }
  // Whether the server closes the connection (within the read timeout) with nothing more sent.
  bool ClosedWithoutMore() {
    while (Fill()) {
    }
    return buffer_.empty() && closed_;
  }

 private:
  static std::string Lower(std::string text) {
    for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return text;
  }
  bool Fill() {
    char chunk[4096];
    const ssize_t n = ::recv(fd_, chunk, sizeof(chunk), 0);
    if (n == 0 || (n < 0 && errno == ECONNRESET)) closed_ = true;
    if (n <= 0) return false;
    buffer_.append(chunk, static_cast<size_t>(n));
    return true;
  }

  int fd_ = -1;
  bool connected_ = false;
  bool closed_ = false;
  std::string buffer_;
};

std::string Post(const std::string& path, const std::string& body,
                 const std::string& extra_headers = "") {
  return "POST " + path + " HTTP/1.1\r\nHost: x\r\nContent-Length: " + std::to_string(body.size()) +
         "\r\n" + extra_headers + "\r\n" + body;
}

class HttpServerTest : public testing::Test {
 protected:
  void Start() {
    HttpCallbacks callbacks;
    callbacks.screen = [](const HttpRequest& head) -> std::optional<HttpResponse> {
      if (head.path != "/screened") return std::nullopt;
      HttpResponse refusal;
      refusal.status = 401;
      refusal.SetContent("screened", "text/plain");
      return refusal;
    };
    callbacks.handle = [](HttpRequest& request, HttpResponse& response) {
      if (request.path == "/deferred") {
        response.deferred = DeferredWork{
            [](HttpResponse& late) { late.SetContent("from the worker", "text/plain"); }, false,
            Clock::now() + std::chrono::seconds(10)};
        return;
      }
      std::string text = request.method + " " + request.path + " " +
                         std::to_string(request.body.size()) + " bytes";
      for (const FormPart& part : request.parts) text += " part " + part.name;
      response.SetContent(text, "text/plain");
    };
    callbacks.defer = [this](DeferredWork work, std::shared_ptr<HttpResponse> response,
                             std::function<void()> done) {
      std::lock_guard<std::mutex> lock(workers_mutex_);
      workers_.emplace_back([work = std::move(work), response, done = std::move(done)] {
        work.work(*response);
        done();
      });
    };
    callbacks.error = [](int status, const std::string& message, const std::string&) {
      HttpResponse response;
      response.status = status;
      response.SetContent(message, "text/plain");
      return response;
    };
    callbacks.log = [](const HttpRequest&, const HttpResponse&, double) {};
    server_.emplace(limits_, std::move(callbacks));
    const std::optional<int> port = server_->Bind("127.0.0.1", 0);
    ASSERT_TRUE(port);
    port_ = *port;
    serving_ = std::thread([this] { server_->Serve(); });
  }
  void TearDown() override {
    if (!server_) return;
    server_->Stop();
    serving_.join();
    for (std::thread& worker : workers_) worker.join();
  }

  HttpLimits limits_;
  std::optional<HttpServer> server_;
  int port_ = 0;
  std::thread serving_;
  std::mutex workers_mutex_;
  std::vector<std::thread> workers_;
};

TEST_F(HttpServerTest, KeepAliveAnswersRequestsInTurnAndParsesMultipart) {
  Start();
  RawClient client(port_);
  ASSERT_TRUE(client.connected());
  const std::string form =
      "--B\r\nContent-Disposition: form-data; name=\"image\"\r\n\r\nxyz\r\n--B--\r\n";
  ASSERT_TRUE(client.Send("GET /a?x=1 HTTP/1.1\r\nHost: x\r\n\r\n" + Post("/b", "12345") +
                          Post("/c", form, "Content-Type: multipart/form-data; boundary=B\r\n")));
  EXPECT_EQ(client.Read().body, "GET /a 0 bytes");
  EXPECT_EQ(client.Read().body, "POST /b 5 bytes");
  EXPECT_EQ(client.Read().body, "POST /c " + std::to_string(form.size()) + " bytes part image");
}

TEST_F(HttpServerTest, ABodyAnnouncedOverTheLimitIsRefusedBeforeItIsSent) {
  limits_.max_body_bytes = 1 << 20;
  Start();
  RawClient client(port_);
  // A gigabyte announced; not one byte of it sent.
  ASSERT_TRUE(client.Send("POST /q HTTP/1.1\r\nHost: x\r\nContent-Length: 1073741824\r\n\r\n"));
  const RawClient::Response response = client.Read();
  EXPECT_EQ(response.status, 413);
  EXPECT_EQ(response.body,
            "the body is too large: 1073741824 bytes, over --max-body-mb (1048576 bytes)");
  EXPECT_NE(response.head.find("Connection: close"), std::string::npos) << response.head;
  EXPECT_TRUE(client.ClosedWithoutMore());
}

TEST_F(HttpServerTest, AChunkedBodyIsRefusedOnceItOutgrowsTheLimit) {
  limits_.max_body_bytes = 1000;
  Start();
  RawClient client(port_);
  ASSERT_TRUE(
      client.Send("POST /q HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n400\r\n" +
                  std::string(1024, 'x') + "\r\n"));
  const RawClient::Response response = client.Read();
  EXPECT_EQ(response.status, 413);
  EXPECT_EQ(response.body, "the body is too large: over --max-body-mb (1000 bytes)");
}

TEST_F(HttpServerTest, HeadersOverTheLimitGet431) {
  limits_.max_header_bytes = 1024;
  Start();
  RawClient client(port_);
  ASSERT_TRUE(client.Send("GET / HTTP/1.1\r\nX-Long: " + std::string(2000, 'a') + "\r\n\r\n"));
  const RawClient::Response response = client.Read();
  EXPECT_EQ(response.status, 431);
  EXPECT_EQ(response.body, "the request line and headers are over 1024 bytes");
}

TEST_F(HttpServerTest, HeadersThatStallGet408AndASilentConnectionIsClosed) {
  limits_.request_timeout_s = 0.3;
  Start();
  RawClient slow(port_), silent(port_);
  ASSERT_TRUE(slow.Send("GET / HTTP/1.1\r\nHost: x\r\nX-Dri"));
  const RawClient::Response response = slow.Read();
  EXPECT_EQ(response.status, 408);
  EXPECT_EQ(response.body, "the request's headers were not read in time");
  EXPECT_TRUE(silent.ClosedWithoutMore());
}

TEST_F(HttpServerTest, ABodySlowerThanTheMinimumRateGets408) {
  limits_.request_timeout_s = 0.2;
  limits_.min_body_rate = 10000;  // 2,000 bytes: 0.2 + 0.2 s
  Start();
  RawClient client(port_);
  ASSERT_TRUE(client.Send("POST /q HTTP/1.1\r\nHost: x\r\nContent-Length: 2000\r\n\r\n" +
                          std::string(100, 'x')));
  const RawClient::Response response = client.Read();
  EXPECT_EQ(response.status, 408);
  EXPECT_EQ(response.body,
            "the request's body was not read in time (--request-timeout, --min-body-rate)");
}

TEST_F(HttpServerTest, AConnectionBeyondTheLimitGets503AtOnceAndTheNextIsServed) {
  limits_.max_connections = 2;
  Start();
  std::optional<RawClient> first(std::in_place, port_);
  RawClient second(port_);
  ASSERT_TRUE(second.Send("GET /held HTTP/1.1\r\nHost: x\r\n\r\n"));
  ASSERT_EQ(second.Read().status, 200);  // both are served (accepted) now
  {
    RawClient third(port_);
    const RawClient::Response response = third.Read();  // without having sent a thing
    EXPECT_EQ(response.status, 503);
    EXPECT_EQ(response.body,
              "busy: 2 connections are served already (--max-connections); retry later");
  }
  first.reset();  // a place frees once the server sees the close
  const auto give_up = Clock::now() + std::chrono::seconds(10);
  int status = 0;
  while (status != 200 && Clock::now() < give_up) {
    RawClient next(port_);
    next.Send("GET /next HTTP/1.1\r\nHost: x\r\n\r\n");
    status = next.Read().status;
    if (status != 200) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(status, 200);
}

TEST_F(HttpServerTest, ExpectContinueGetsA100ThenTheAnswer) {
  Start();
  RawClient client(port_);
  ASSERT_TRUE(client.Send(
      "POST /q HTTP/1.1\r\nHost: x\r\nContent-Length: 3\r\nExpect: 100-continue\r\n\r\n"));
  EXPECT_EQ(client.Read().status, 100);
  ASSERT_TRUE(client.Send("abc"));
  EXPECT_EQ(client.Read().body, "POST /q 3 bytes");
}

TEST_F(HttpServerTest, ScreenedRequestsAreAnsweredWithoutTheirBodyAndTheConnectionEnds) {
  Start();
  RawClient client(port_);
  ASSERT_TRUE(client.Send("POST /screened HTTP/1.1\r\nHost: x\r\nContent-Length: 100000\r\n\r\n"));
  const RawClient::Response response = client.Read();
  EXPECT_EQ(response.status, 401);
  EXPECT_EQ(response.body, "screened");
  EXPECT_TRUE(client.ClosedWithoutMore());  // the unread body is no next request
}

TEST_F(HttpServerTest, DeferredWorkIsAnsweredWhenTheWorkerIsDone) {
  Start();
  RawClient client(port_);
  ASSERT_TRUE(
      client.Send("GET /deferred HTTP/1.1\r\nHost: x\r\n\r\n"
                  "GET /after HTTP/1.1\r\nHost: x\r\n\r\n"));
  EXPECT_EQ(client.Read().body, "from the worker");
  EXPECT_EQ(client.Read().body, "GET /after 0 bytes");
}

TEST_F(HttpServerTest, StopEndsIdleConnectionsAndServeReturns) {
  Start();
  RawClient idle(port_);
  ASSERT_TRUE(idle.Send("GET / HTTP/1.1\r\nHost: x\r\n\r\n"));
  ASSERT_EQ(idle.Read().status, 200);
  server_->Stop();
  serving_.join();  // would hang while the idle connection were kept
  EXPECT_TRUE(idle.ClosedWithoutMore());
  server_.reset();
}

// The fuzzer's entry reads bytes as a connection does.
TEST(ParseRequestBytes, ReadsTheQueryTheHeadersAndTheMultipartParts) {
  const std::string body =
      "--XX\r\nContent-Disposition: form-data; name=\"options\"\r\n\r\n{\"top_k\": 3}\r\n"
      "--XX--\r\n";
  const std::string bytes =
      "POST /localize?x=1&y=%41+b HTTP/1.1\r\nHost: a\r\n"
      "Content-Type: multipart/form-data; boundary=XX\r\nContent-Length: " +
      std::to_string(body.size()) + "\r\n\r\n" + body;
  const std::optional<HttpRequest> request = ParseRequestBytes(bytes, HttpLimits());
  ASSERT_TRUE(request);
  EXPECT_EQ(request->method, "POST");
  EXPECT_EQ(request->path, "/localize");
  EXPECT_EQ(request->Param("y"), "A b");
  EXPECT_EQ(request->Header("host"), "a");
  ASSERT_EQ(request->parts.size(), 1u);
  EXPECT_EQ(request->parts[0].name, "options");
  EXPECT_EQ(request->parts[0].content, R"({"top_k": 3})");
  // Cut short: no request yet.
  EXPECT_FALSE(ParseRequestBytes(bytes.substr(0, bytes.size() - 3), HttpLimits()));
}

TEST(ParseRequestBytes, RefusesWhatAConnectionRefuses) {
  HttpLimits limits;
  limits.max_body_bytes = 4;
  try {
    ParseRequestBytes("POST / HTTP/1.1\r\nContent-Length: 5\r\n\r\nhello", limits);
    FAIL() << "a body over the limit was read";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "HTTP request: body limit exceeded");
  }
  try {
    ParseRequestBytes("GET /%zz HTTP/1.1\r\n\r\n", limits);
    FAIL() << "a malformed escape was read";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "HTTP request: a malformed URL escape in the request's target");
  }
}

}  // namespace
}  // namespace cwloc
