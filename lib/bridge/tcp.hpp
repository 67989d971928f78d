// A raw TCP port for `dpc31 bridge` (docs/bridge.md, "Over TCP"): for DP master programs that
// cannot open a pty (pyserial's socket://HOST:PORT URL, a master on another machine's serial
// server protocol). The same byte stream as the pty, no framing of its own; one client at a
// time: a second connection while one is there is accepted and closed at once, with a NOTE.
// The bridge has no authentication: it listens on the loopback unless told otherwise.
#pragma once

#include <string>

#include "port.hpp"
#include "pty.hpp"  // PtyError

namespace dpc31::bridge {

struct ListenAddress {
  std::string host = "127.0.0.1";  // numeric: 127.0.0.1, ::1, 0.0.0.0, ...
  unsigned port = 0;               // 0: the kernel picks one (the log's first line names it)
};

// "PORT", "HOST:PORT" or "[V6HOST]:PORT" into `a`; "" or a one-line reason it is not one.
std::string parse_listen(const std::string& text, ListenAddress& a);
// Whether a numeric host is a loopback address (127.0.0.0/8, ::1).
bool is_loopback(const std::string& host);

class TcpPort final : public ClientPort {
 public:
  // Binds and listens (non-blocking, close-on-exec, SO_REUSEADDR). Throws PtyError.
  explicit TcpPort(const ListenAddress& a);
  ~TcpPort() override;
  TcpPort(const TcpPort&) = delete;
  TcpPort& operator=(const TcpPort&) = delete;

  [[nodiscard]] std::string describe() const override;  // "tcp 127.0.0.1:40123"
  [[nodiscard]] std::vector<pollfd> poll_fds() const override;
  void service(std::span<const pollfd> fds, const PortEvents& ev) override;
  [[nodiscard]] bool present() const override { return client_ >= 0; }
  std::size_t write(std::span<const std::uint8_t> bytes) override;
  [[nodiscard]] bool sent_all() const override { return client_ >= 0 && sent_all_; }
  void hang_up(const PortEvents& ev) override { drop_client(ev, "closed the connection"); }
  [[nodiscard]] unsigned port() const { return port_; }  // the bound port

 private:
  void accept_one(const PortEvents& ev);
  void read_client(const PortEvents& ev);
  // ACK what was read at once (TCP_QUICKACK), not after the delayed-ACK timer.
  void quick_ack() const;
  void drop_client(const PortEvents& ev, const std::string& why);
  int listen_ = -1;
  int client_ = -1;
  bool sent_all_ = false;  // the client half-closed: no more bytes come, its answers still go
  std::string host_;
  unsigned port_ = 0;
  std::string peer_;  // "127.0.0.1:51234"
};

}  // namespace dpc31::bridge
