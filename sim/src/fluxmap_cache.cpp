// A disk cache for tabulate_flux_map (sim/include/mcsim/fluxmap.hpp): on a short run, tabulating
// the estimator's map (1681 Newton solves of psi(i)) was a third of the instructions.
//
// Key: the grid, the model's type and its flux at 25 probe currents spread over the grid, to the
// bit (two models that agree there to the last bit are taken as the same: for the parametric
// models here that means the same parameters). Value: the table's doubles, exact, so a cached
// run is bit-identical to a fresh one. Where: $MCSIM_CACHE_DIR, else $XDG_CACHE_HOME/mcsim, else
// $HOME/.cache/mcsim; MCSIM_CACHE=off switches it off. Written to a temporary file and renamed,
// so parallel runs never read half a file; anything that does not read back exactly (size,
// header, grid) is recomputed and rewritten; a folder that cannot be written is not an error.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <typeinfo>
#include <vector>

#include <unistd.h>

#include "mcsim/fluxmap.hpp"

namespace mcsim {
namespace {

constexpr std::uint64_t kMagic = 0x31504d584c46434dULL;   // "MCFLXMP1"
// Raise it whenever tabulate_flux_map computes differently (its solver, tolerances): the key
// sees the model, not the code that tabulates it.
constexpr std::uint32_t kVersion = 1;

std::uint64_t fnv1a(const void* p, size_t n, std::uint64_t h)
{
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t k = 0; k < n; ++k) {
        h ^= b[k];
        h *= 1099511628211ULL;
    }
    return h;
}

std::filesystem::path cache_dir()
{
    const char* off = std::getenv("MCSIM_CACHE");
    if (off && (std::strcmp(off, "off") == 0 || std::strcmp(off, "0") == 0)) return {};
    if (const char* d = std::getenv("MCSIM_CACHE_DIR"); d && *d) return d;
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::filesystem::path(x) / "mcsim";
    if (const char* h = std::getenv("HOME"); h && *h) return std::filesystem::path(h) / ".cache" / "mcsim";
    return {};
}

struct Header {
    std::uint64_t magic;
    std::uint32_t version, nd, nq, pad;
    double d_lo, d_hi, q_lo, q_hi;
    std::uint64_t key;
};

std::uint64_t model_key(const FluxModel& m, const GridAxis& id, const GridAxis& iq)
{
    std::uint64_t h = 14695981039346656037ULL;
    const char* type = typeid(m).name();
    h = fnv1a(type, std::strlen(type), h);
    const double g[6] = {id.lo, id.hi, double(id.n), iq.lo, iq.hi, double(iq.n)};
    h = fnv1a(g, sizeof g, h);
    for (int a = 0; a < 5; ++a) {
        for (int b = 0; b < 5; ++b) {
            // irregular fractions of the span, so that no probe sits on a symmetry line
            const Vec2 i(id.lo + (id.hi - id.lo) * (0.07 + 0.21 * a), iq.lo + (iq.hi - iq.lo) * (0.11 + 0.19 * b));
            const Vec2 psi = m.flux(i);
            const double v[2] = {psi.x(), psi.y()};
            h = fnv1a(v, sizeof v, h);
        }
    }
    return h;
}

}  // namespace

FluxMapTable tabulate_flux_map_cached(const FluxModel& m, const GridAxis& id, const GridAxis& iq)
{
    const std::filesystem::path dir = cache_dir();
    if (dir.empty()) return tabulate_flux_map(m, id, iq);
    const std::uint64_t key = model_key(m, id, iq);
    char name[40];
    std::snprintf(name, sizeof name, "fluxmap-%016llx.bin", static_cast<unsigned long long>(key));
    const std::filesystem::path file = dir / name;
    const size_t n = size_t(id.n) * size_t(iq.n);
    {
        std::ifstream in(file, std::ios::binary);
        Header h{};
        std::vector<double> v(2 * n);
        if (in && in.read(reinterpret_cast<char*>(&h), sizeof h) &&
            in.read(reinterpret_cast<char*>(v.data()), std::streamsize(v.size() * sizeof(double))) &&
            in.peek() == std::char_traits<char>::eof() && h.magic == kMagic && h.version == kVersion &&
            h.nd == std::uint32_t(id.n) && h.nq == std::uint32_t(iq.n) && h.d_lo == id.lo && h.d_hi == id.hi &&
            h.q_lo == iq.lo && h.q_hi == iq.hi && h.key == key) {
            FluxMapTable t(TableKind::FluxOfCurrent, id, iq);
            for (int a = 0; a < id.n; ++a)
                for (int b = 0; b < iq.n; ++b)
                    t.set_node(a, b, Vec2(v[2 * (size_t(a) * size_t(iq.n) + size_t(b))],
                                          v[2 * (size_t(a) * size_t(iq.n) + size_t(b)) + 1]));
            return t;
        }
    }
    FluxMapTable t = tabulate_flux_map(m, id, iq);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return t;
    const Header h{kMagic, kVersion, std::uint32_t(id.n), std::uint32_t(iq.n), 0, id.lo, id.hi, iq.lo, iq.hi, key};
    std::vector<double> v(2 * n);
    for (int a = 0; a < id.n; ++a)
        for (int b = 0; b < iq.n; ++b) {
            const Vec2 p = t.node(a, b);
            v[2 * (size_t(a) * size_t(iq.n) + size_t(b))] = p.x();
            v[2 * (size_t(a) * size_t(iq.n) + size_t(b)) + 1] = p.y();
        }
    const std::filesystem::path tmp = dir / (std::string(name) + ".tmp" + std::to_string(::getpid()));
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) return t;
        out.write(reinterpret_cast<const char*>(&h), sizeof h);
        out.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(double)));
        if (!out) {
            out.close();
            std::filesystem::remove(tmp, ec);
            return t;
        }
    }
    std::filesystem::rename(tmp, file, ec);
    if (ec) std::filesystem::remove(tmp, ec);
    return t;
}

}  // namespace mcsim
