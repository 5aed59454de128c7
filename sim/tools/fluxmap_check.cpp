// fluxmap-check: read and check a measured flux map (a preset's [flux_map] file) with the
// simulator's reader and print what it derives, as one JSON object on stdout:
//   fluxmap-check MAP.csv
// {"file", "n_d", "n_q", "i_d_lo", "i_d_hi", "i_q_lo", "i_q_hi", "psi_pm", "psi_q0", "ld", "lq", "ldq",
//  "recip_rms", "recip_max", "recip_max_id", "recip_max_iq", "warnings": [...]} (17 significant digits).
// A refused map: the reader's message on stderr, exit status 2. tools/tests/test_fluxmap.py runs
// this and mctools.fluxmap on the same files and compares the two.
#include <cstdio>
#include <exception>
#include <string>

#include "mcsim/fluxmap_file.hpp"

namespace {
std::string json_str(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') o += '\\';
        if (static_cast<unsigned char>(c) < 0x20) {
            char b[8];
            std::snprintf(b, sizeof b, "\\u%04x", c);
            o += b;
            continue;
        }
        o += c;
    }
    return o + "\"";
}
}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: fluxmap-check MAP.csv\n");
        return 2;
    }
    try {
        const mcsim::FluxMapData d = mcsim::read_flux_map_file(argv[1]);
        const auto& t = d.table;
        std::printf("{\"file\": %s, \"n_d\": %d, \"n_q\": %d, \"i_d_lo\": %.17g, \"i_d_hi\": %.17g, \"i_q_lo\": %.17g, "
                    "\"i_q_hi\": %.17g, \"psi_pm\": %.17g, \"psi_q0\": %.17g, \"ld\": %.17g, \"lq\": %.17g, "
                    "\"ldq\": %.17g, \"recip_rms\": %.17g, \"recip_max\": %.17g, \"recip_max_id\": %.17g, "
                    "\"recip_max_iq\": %.17g, \"warnings\": [",
                    json_str(d.file).c_str(), t.x.n, t.y.n, t.x.lo, t.x.hi, t.y.lo, t.y.hi, d.psi_pm, d.psi_q0, d.ld,
                    d.lq, d.ldq, d.recip_rms, d.recip_max, d.recip_max_id, d.recip_max_iq);
        for (size_t k = 0; k < d.warnings.size(); ++k)
            std::printf("%s%s", k ? ", " : "", json_str(d.warnings[k]).c_str());
        std::printf("]}\n");
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 2;
    }
}
