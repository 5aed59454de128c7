// CAN links of the simulated drive (can_link.hpp).
#include "can_link.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#if __has_include(<linux/can.h>)
#include <linux/can.h>
#include <linux/can/raw.h>
#define MCSIM_HAVE_SOCKETCAN 1
#endif

#include "scenario.hpp"

namespace mcsim {

namespace {

void set_nonblocking(int fd)
{
    const int fl = fcntl(fd, F_GETFL, 0);
    fcntl(fd, F_SETFL, fl | O_NONBLOCK);
}

// socketcand's ASCII protocol, raw mode (https://github.com/linux-can/socketcand, doc/protocol.md)
// as python-can's client speaks it: `< hi >` on connect; `< open can0 >` -> `< ok >`;
// `< rawmode >` -> `< ok >` (the client is subscribed before the ok, so no frame is lost); then
// `< frame ID SEC.USEC DATA >` to the client (ID: 3 hex digits, 8 for extended; DATA contiguous hex)
// and `< send ID DLC B0 B1 ... >` from it (hex, either case). Never `< error ... >` in raw mode:
// python-can's client would take it for a frame; a bad command is dropped and counted.
class Socketcand final : public CanLink {
public:
    Socketcand(const std::string& host, int port) : host_(host), port_(port)
    {
        addrinfo hints{};
        hints.ai_family = AF_INET;
        hints.ai_socktype = SOCK_STREAM;
        addrinfo* res = nullptr;
        if (getaddrinfo(host.c_str(), nullptr, &hints, &res) != 0 || res == nullptr)
            throw ScenarioError("--can socketcand:" + host + ":" + std::to_string(port) + ": cannot resolve '" + host + "'");
        sockaddr_in a = *reinterpret_cast<sockaddr_in*>(res->ai_addr);
        freeaddrinfo(res);
        a.sin_port = htons(static_cast<uint16_t>(port));
        lfd_ = socket(AF_INET, SOCK_STREAM, 0);
        const int one = 1;
        setsockopt(lfd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        if (lfd_ < 0 || bind(lfd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || listen(lfd_, 8) != 0) {
            const std::string why = std::strerror(errno);
            if (lfd_ >= 0) close(lfd_);
            throw ScenarioError("--can socketcand:" + host + ":" + std::to_string(port) + ": cannot listen (" + why + ")");
        }
        set_nonblocking(lfd_);
    }
    ~Socketcand() override
    {
        for (Client& c : clients_)
            if (c.fd >= 0) close(c.fd);
        if (lfd_ >= 0) close(lfd_);
    }

    // Like a bus (and the real socketcand): every raw-mode client sees the drive's frames and
    // the other clients' frames, so a monitor and a tuning tool can be connected at once.
    void pump(hal_can_t* can, double t) override
    {
        accept_clients();
        const auto now = std::chrono::steady_clock::now();
        for (Client& c : clients_)
            if (c.fd >= 0 && !c.held.empty() && now >= c.hold_until) {
                send_line(c, c.held);
                c.held.clear();
            }
        for (size_t k = 0; k < clients_.size(); ++k) read_client(k, can, t);
        hal_can_frame_t f;
        while (hal_host_can_take(can, &f)) broadcast(frame_line(f, t), clients_.size());
        clients_.erase(std::remove_if(clients_.begin(), clients_.end(), [](const Client& c) { return c.fd < 0; }),
                       clients_.end());
    }

    std::string describe() const override
    {
        return "socketcand on " + host_ + ":" + std::to_string(port_) + " (channel can0, raw mode, up to " +
               std::to_string(kMaxClients) + " clients)";
    }

private:
    static constexpr size_t kMaxClients = 8;
    // After `< rawmode >` is acknowledged a client's frames are held back for a moment (and then
    // sent, none lost): python-can's client reads the `< ok >` with one recv() and compares it
    // whole, so a frame in the same TCP segment would fail its handshake.
    static constexpr std::chrono::milliseconds kHold{100};
    struct Client {
        int fd = -1;
        bool raw = false;
        std::string in;
        std::chrono::steady_clock::time_point hold_until{};
        std::string held;
    };

    static std::string frame_line(const hal_can_frame_t& f, double t)
    {
        char id[16];
        std::snprintf(id, sizeof id, f.ext ? "%08X" : "%03X", static_cast<unsigned>(f.id));
        const double sec = t < 0 ? 0 : t;
        const long s = static_cast<long>(sec);
        char ts[40];
        std::snprintf(ts, sizeof ts, "%ld.%06ld", s, static_cast<long>((sec - static_cast<double>(s)) * 1e6));
        std::string data;
        for (int k = 0; k < f.dlc && !f.rtr; ++k) {
            char b[4];
            std::snprintf(b, sizeof b, "%02X", f.data[k]);
            data += b;
        }
        return std::string("< frame ") + id + " " + ts + " " + data + " >";
    }

    void accept_clients()
    {
        for (;;) {
            const int fd = accept(lfd_, nullptr, nullptr);
            if (fd < 0) return;
            if (clients_.size() >= kMaxClients) {
                close(fd);   // refused: the client sees the connection closed
                continue;
            }
            set_nonblocking(fd);
            const int one = 1;
            setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
            Client c;
            c.fd = fd;
            clients_.push_back(c);
            send_line(clients_.back(), "< hi >");
        }
    }

    static void drop(Client& c)
    {
        close(c.fd);
        c.fd = -1;
        c.raw = false;
        c.in.clear();
    }

    // A line goes out whole; a client that stops reading for a second is dropped rather than
    // stalling the simulation.
    static void send_line(Client& c, const std::string& line)
    {
        size_t off = 0;
        while (c.fd >= 0 && off < line.size()) {
            const ssize_t n = ::send(c.fd, line.data() + off, line.size() - off, MSG_NOSIGNAL);
            if (n < 0) {
                pollfd p{c.fd, POLLOUT, 0};
                if ((errno == EAGAIN || errno == EWOULDBLOCK) && poll(&p, 1, 1000) == 1) continue;
                drop(c);
                return;
            }
            off += static_cast<size_t>(n);
        }
    }

    // To every raw-mode client but `except` (an index; clients_.size(): none).
    void broadcast(const std::string& line, size_t except)
    {
        const auto now = std::chrono::steady_clock::now();
        for (size_t k = 0; k < clients_.size(); ++k) {
            Client& c = clients_[k];
            if (k == except || c.fd < 0 || !c.raw) continue;
            if (now < c.hold_until) {
                if (c.held.size() < (1u << 20)) c.held += line;   // a second of a busy bus at most
            } else {
                send_line(c, line);
            }
        }
    }

    void read_client(size_t k, hal_can_t* can, double t)
    {
        if (clients_[k].fd < 0) return;
        char buf[4096];
        for (;;) {
            const ssize_t n = recv(clients_[k].fd, buf, sizeof buf, 0);
            if (n == 0) {
                drop(clients_[k]);
                return;
            }
            if (n < 0) break;
            clients_[k].in.append(buf, static_cast<size_t>(n));
        }
        // complete commands: "< ... >"
        for (;;) {
            std::string& in = clients_[k].in;
            const size_t a = in.find('<');
            if (a == std::string::npos) {
                in.clear();
                return;
            }
            const size_t b = in.find('>', a);
            if (b == std::string::npos) {
                in.erase(0, a);
                return;
            }
            const std::string body = in.substr(a + 1, b - a - 1);
            in.erase(0, b + 1);
            command(k, body, can, t);
            if (clients_[k].fd < 0) return;
        }
    }

    void command(size_t k, const std::string& body, hal_can_t* can, double t)
    {
        std::vector<std::string> w;
        size_t i = 0;
        while (i < body.size()) {
            while (i < body.size() && body[i] == ' ') ++i;
            size_t e = i;
            while (e < body.size() && body[e] != ' ') ++e;
            if (e > i) w.push_back(body.substr(i, e - i));
            i = e;
        }
        if (w.empty()) return;
        Client& c = clients_[k];
        if (w[0] == "open" && w.size() == 2) {
            send_line(c, "< ok >");
        } else if (w[0] == "rawmode") {
            c.raw = true;   // subscribed first, then acknowledged
            c.hold_until = std::chrono::steady_clock::now() + kHold;
            send_line(c, "< ok >");
        } else if (w[0] == "send" && w.size() >= 3) {
            hal_can_frame_t f{};
            char* end = nullptr;
            const unsigned long id = std::strtoul(w[1].c_str(), &end, 16);
            const unsigned long dlc = std::strtoul(w[2].c_str(), nullptr, 16);
            if (*end != '\0' || dlc > 8 || w.size() != 3 + dlc) {
                ++bad_;
                return;
            }
            f.ext = w[1].size() > 3 || id > 0x7FF;
            f.id = static_cast<uint32_t>(id);
            f.dlc = static_cast<uint8_t>(dlc);
            for (unsigned long j = 0; j < dlc; ++j)
                f.data[j] = static_cast<uint8_t>(std::strtoul(w[3 + j].c_str(), nullptr, 16));
            if (!hal_can_frame_valid(&f)) {
                ++bad_;
                return;
            }
            if (!hal_host_can_deliver(can, &f)) ++bad_;   // the drive's RX ring full: lost for it
            broadcast(frame_line(f, t), k);               // the other clients see it on the bus
        } else {
            ++bad_;   // not for raw mode (bcm, echo, ...): ignored, never answered with < error >
        }
    }

    std::string host_;
    int port_;
    int lfd_ = -1;
    std::vector<Client> clients_;
    unsigned long bad_ = 0;
};

#ifdef MCSIM_HAVE_SOCKETCAN
class SocketCan final : public CanLink {
public:
    explicit SocketCan(const std::string& iface) : iface_(iface)
    {
        fd_ = socket(PF_CAN, SOCK_RAW, CAN_RAW);
        if (fd_ < 0)
            throw ScenarioError("--can socketcan:" + iface + ": this kernel has no CAN sockets (" + std::strerror(errno) +
                                "); use --can socketcand:127.0.0.1:29536");
        ifreq ifr{};
        std::snprintf(ifr.ifr_name, IFNAMSIZ, "%s", iface.c_str());
        if (ioctl(fd_, SIOCGIFINDEX, &ifr) < 0) {
            close(fd_);
            throw ScenarioError("--can socketcan:" + iface + ": no such CAN interface (" + std::strerror(errno) + ")");
        }
        sockaddr_can a{};
        a.can_family = AF_CAN;
        a.can_ifindex = ifr.ifr_ifindex;
        if (bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0) {
            close(fd_);
            throw ScenarioError("--can socketcan:" + iface + ": cannot bind (" + std::strerror(errno) + ")");
        }
        set_nonblocking(fd_);
    }
    ~SocketCan() override { close(fd_); }
    void pump(hal_can_t* can, double) override
    {
        can_frame cf;
        while (read(fd_, &cf, sizeof cf) == static_cast<ssize_t>(sizeof cf)) {
            hal_can_frame_t f{};
            f.ext = (cf.can_id & CAN_EFF_FLAG) != 0;
            f.rtr = (cf.can_id & CAN_RTR_FLAG) != 0;
            f.id = cf.can_id & (f.ext ? CAN_EFF_MASK : CAN_SFF_MASK);
            f.dlc = cf.can_dlc > 8 ? 8 : cf.can_dlc;
            std::memcpy(f.data, cf.data, 8);
            if (!(cf.can_id & CAN_ERR_FLAG)) hal_host_can_deliver(can, &f);
        }
        hal_can_frame_t f;
        while (hal_host_can_take(can, &f)) {
            can_frame o{};
            o.can_id = f.id | (f.ext ? CAN_EFF_FLAG : 0u) | (f.rtr ? CAN_RTR_FLAG : 0u);
            o.can_dlc = f.dlc;
            std::memcpy(o.data, f.data, 8);
            (void)!write(fd_, &o, sizeof o);
        }
    }
    std::string describe() const override { return "SocketCAN interface " + iface_; }

private:
    std::string iface_;
    int fd_ = -1;
};
#endif

}  // namespace

std::unique_ptr<CanLink> make_can_link(const std::string& spec)
{
    const std::string bad = "--can '" + spec + "': expected socketcand:HOST:PORT (e.g. socketcand:127.0.0.1:29536) or socketcan:IFACE";
    if (spec.rfind("socketcand:", 0) == 0) {
        const std::string rest = spec.substr(11);
        const size_t c = rest.rfind(':');
        if (c == std::string::npos || c == 0) throw ScenarioError(bad);
        char* end = nullptr;
        const long port = std::strtol(rest.c_str() + c + 1, &end, 10);
        if (*end != '\0' || port < 1 || port > 65535) throw ScenarioError(bad + ": the port must be 1..65535");
        return std::make_unique<Socketcand>(rest.substr(0, c), static_cast<int>(port));
    }
    if (spec.rfind("socketcan:", 0) == 0 && spec.size() > 10) {
#ifdef MCSIM_HAVE_SOCKETCAN
        return std::make_unique<SocketCan>(spec.substr(10));
#else
        throw ScenarioError("--can " + spec + ": this build has no SocketCAN headers");
#endif
    }
    throw ScenarioError(bad);
}

}  // namespace mcsim
