// mcsim: scenario runner CLI.
//   mcsim run SCENARIO.toml [--set key=value]... [--out DIR] [--quiet] [--pil IMAGE.elf]
//             [--can socketcand:HOST:PORT | socketcan:IFACE] [--realtime[=SCALE]] [--nvm FILE]
//   mcsim bench [--seconds S] [--repeat N] [--integrator taylor|hermite|rk4]
//   mcsim keys                      (the scenario key table, markdown)
//   mcsim params                    (the firmware's parameter table, markdown)
//   mcsim check SCENARIO.toml [--set key=value]...   (validate only)
//   mcsim image-config SCENARIO.toml --image IN.elf --out OUT.elf [--set key=value]...
// Exit status: 0 done, 2 bad input (scenario, key, value, file), 1 failure while running.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "drive_setup.hpp"
#include "image_config.hpp"
#include "runner.hpp"
#include "scenario.hpp"

extern "C" {
#include "mc/sincos.h"
}
#include <chrono>
#include <cmath>

namespace {

// ns per call of f over a fixed angle sweep, best of several chunks (preemption only adds time).
template <class F>
double ns_per_call(F f)
{
    constexpr int n = 4096;
    volatile float sink = 0.0f;
    double best = 1e30;
    for (int rep = 0; rep < 200; ++rep) {
        float acc = 0.0f;
        const auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < n; ++k) acc += f(static_cast<float>(k) * 0.0302f - 61.0f);
        const double dt = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
        sink = sink + acc;
        best = std::min(best, dt / n);
    }
    return best;
}

const char* kUsage =
    "usage: mcsim run SCENARIO.toml [--set key=value]... [--out DIR] [--quiet] [--pil IMAGE.elf]\n"
    "                 [--can socketcand:HOST:PORT | socketcan:IFACE] [--realtime[=SCALE]] [--nvm FILE]\n"
    "         --can socketcand:HOST:PORT | socketcan:IFACE: the drive on a CAN bus (python-can reaches it)\n"
    "         --realtime[=SCALE]: pace simulated time to the wall clock (x SCALE)\n"
    "         --nvm FILE: the drive's NVM (CANopen store 0x1010) kept in FILE across runs; the drive boots\n"
    "                     with the set stored there\n"
    "         --pil: run a cross-built firmware image (presets arm-cm4f, am263x) on an emulated core\n"
    "                against the plant instead of the host build; adds estimated ISR cycles to metrics.json\n"
    "                --pil IMAGE.appimage: boot mode, the AM263x boot image loaded as TI's SBL loads it (its\n"
    "                sections at their run addresses, nothing else); symbols from IMAGE.elf beside it\n"
    "       mcsim check SCENARIO.toml [--set key=value]...\n"
    "       mcsim image-config SCENARIO.toml --image IN.elf --out OUT.elf [--set key=value]...\n"
    "                (the scenario's drive configuration written into a firmware image, for flashing)\n"
    "       mcsim bench [--seconds S] [--repeat N] [--integrator taylor|hermite|rk4]\n"
    "       mcsim keys      (the scenario keys)\n"
    "       mcsim params    (the drive's parameter table: ids, CANopen objects, rules)\n"
    "       mcsim faults    (the drive's fault table: bits, metrics names, reactions)\n";

// The standard closed-loop benchmark: encoder FOC speed step 0 -> 600 rpm with 76 % rated load,
// default realism profile (switching inverter with 0.5 us dead time, 12-bit ADC, noise), 10 kHz.
const char* kBenchScenario = R"(
[scenario]
name = "bench: speed step 0->600 rpm, 76 % load, switching inverter"
duration_s = 2.0
[mechanics]
mode = "inertia"
load_torque_nm = [[0.0, 0.0], [0.05, 0.0], [0.05, 22.57]]
[control]
mode = "speed"
speed_ref_rpm = [[0.0, 0.0], [0.1, 0.0], [0.1, 600.0]]
[output]
trace = false
)";

int cmd_run(int argc, char** argv, bool check_only)
{
    std::string file, out, pil, can, nvm;
    double realtime = 0.0;
    std::vector<std::string> sets;
    bool quiet = false;
    for (int k = 2; k < argc; ++k) {
        const std::string a = argv[k];
        if (a == "--set" && k + 1 < argc) sets.push_back(argv[++k]);
        else if (a.rfind("--set=", 0) == 0) sets.push_back(a.substr(6));
        else if (a == "--out" && k + 1 < argc) out = argv[++k];
        else if (a == "--quiet") quiet = true;
        else if (a == "--pil" && k + 1 < argc) pil = argv[++k];
        else if (a == "--can" && k + 1 < argc) can = argv[++k];
        else if (a == "--nvm" && k + 1 < argc) nvm = argv[++k];
        else if (a == "--realtime") realtime = 1.0;
        else if (a.rfind("--realtime=", 0) == 0) {
            char* end = nullptr;
            realtime = std::strtod(a.c_str() + 11, &end);
            if (*end != '\0' || !(realtime > 0.0 && realtime <= 1000.0)) {
                std::fprintf(stderr, "mcsim: --realtime=%s: expected a scale factor in (0, 1000]\n%s", a.c_str() + 11, kUsage);
                return 2;
            }
        }
        else if (a.rfind("--pil=", 0) == 0) pil = a.substr(6);
        else if (!a.empty() && a[0] != '-' && file.empty()) file = a;
        else {
            std::fprintf(stderr, "mcsim: unexpected argument '%s'\n%s", a.c_str(), kUsage);
            return 2;
        }
    }
    if (file.empty()) {
        std::fprintf(stderr, "mcsim: missing SCENARIO.toml\n%s", kUsage);
        return 2;
    }
    const mcsim::Scenario sc = mcsim::Scenario::load(file, sets);
    if (check_only) {
        mcsim::check_scenario(sc);
        std::printf("%s: ok\n", file.c_str());
        return 0;
    }
    if (out.empty()) out = "out/" + std::filesystem::path(file).stem().string();
    if (!quiet) std::fprintf(stderr, "mcsim: running %s (%.3f s simulated)\n", file.c_str(), sc.f("scenario.duration_s"));
    mcsim::RunOptions opt;
    opt.out_dir = out;
    opt.progress = !quiet;
    opt.pil_elf = pil;
    opt.can = can;
    opt.realtime = realtime;
    opt.nvm_file = nvm;
    const mcsim::RunSummary r = mcsim::run_scenario(sc, opt);
    if (!quiet) {
        std::printf("%s", r.metrics_json.c_str());
        std::printf("mcsim: %.3f s simulated in %.2f s (%.0fx real time); wrote %s/metrics.json%s\n", r.sim_time_s,
                    r.wall_time_s, r.realtime_factor, out.c_str(), sc.b("output.trace") ? " and trace.csv" : "");
    }
    return 0;
}

int cmd_image_config(int argc, char** argv)
{
    std::string file, in, out;
    std::vector<std::string> sets;
    for (int k = 2; k < argc; ++k) {
        const std::string a = argv[k];
        if (a == "--set" && k + 1 < argc) sets.push_back(argv[++k]);
        else if (a == "--image" && k + 1 < argc) in = argv[++k];
        else if (a == "--out" && k + 1 < argc) out = argv[++k];
        else if (!a.empty() && a[0] != '-' && file.empty()) file = a;
        else {
            std::fprintf(stderr, "mcsim image-config: unexpected argument '%s'\n%s", a.c_str(), kUsage);
            return 2;
        }
    }
    if (file.empty() || in.empty() || out.empty()) {
        std::fprintf(stderr, "mcsim image-config: needs SCENARIO.toml, --image IN.elf and --out OUT.elf\n%s", kUsage);
        return 2;
    }
    const mcsim::Scenario sc = mcsim::Scenario::load(file, sets);
    const std::vector<uint8_t> area = mcsim::config_area_bytes(sc);
    mcsim::patch_image_config(in, out, area);
    std::printf("mcsim image-config: %s with the configuration of %s (%zu bytes in .mc_config); raw binary: "
                "arm-none-eabi-objcopy -O binary %s OUT.bin\n",
                out.c_str(), file.c_str(), area.size(), out.c_str());
    return 0;
}

int cmd_bench(int argc, char** argv)
{
    double seconds = 2.0;
    int repeat = 3;
    std::string integrator = "taylor";  // the scenario default
    for (int k = 2; k < argc; ++k) {
        const std::string a = argv[k];
        if (a == "--seconds" && k + 1 < argc) {
            seconds = std::atof(argv[++k]);
        } else if (a == "--repeat" && k + 1 < argc) {
            repeat = std::atoi(argv[++k]);
        } else if (a == "--integrator" && k + 1 < argc) {
            integrator = argv[++k];
            if (integrator != "taylor" && integrator != "hermite" && integrator != "rk4") {
                std::fprintf(stderr, "mcsim bench: --integrator '%s': expected taylor, hermite or rk4 (ripple was removed)\n%s",
                             mcsim::message_text(integrator).c_str(), kUsage);
                return 2;
            }
        } else {
            std::fprintf(stderr, "mcsim bench: unexpected argument '%s'\n%s", a.c_str(), kUsage);
            return 2;
        }
    }
    if (!(seconds >= 0.2 && seconds <= 600)) {
        std::fprintf(stderr, "mcsim bench: --seconds %g out of range [0.2, 600]\n", seconds);
        return 2;
    }
    if (repeat < 1 || repeat > 50) {
        std::fprintf(stderr, "mcsim bench: --repeat %d out of range [1, 50]\n", repeat);
        return 2;
    }
    const mcsim::Scenario sc = mcsim::Scenario::from_string(
        kBenchScenario, "(built-in bench)",
        {"scenario.duration_s=" + std::to_string(seconds), "inverter.integrator=\"" + integrator + "\""});
    mcsim::RunOptions opt;  // no files, no progress: measure the loop only
    // A shared machine's load comes and goes: the same run is repeated and the median reported
    // (the spread says how noisy the machine was meanwhile).
    std::vector<mcsim::RunSummary> runs;
    for (int k = 0; k < repeat; ++k) runs.push_back(mcsim::run_scenario(sc, opt));
    std::sort(runs.begin(), runs.end(), [](const mcsim::RunSummary& a, const mcsim::RunSummary& b) {
        return a.realtime_factor < b.realtime_factor;
    });
    const mcsim::RunSummary& r = runs[runs.size() / 2];
    std::printf("mcsim bench: %s\n", sc.s("scenario.name").c_str());
    std::printf("  simulated %.3f s (%ld periods at %.0f Hz) in %.3f s wall on one core (median of %d runs)\n",
                r.sim_time_s, r.periods, r.periods / r.sim_time_s, r.wall_time_s, repeat);
    std::printf("  real-time factor: %.0fx (simulated seconds per wall second; runs: %.0fx .. %.0fx)\n",
                r.realtime_factor, runs.front().realtime_factor, runs.back().realtime_factor);
    const double per_period_ns = r.periods > 0 ? r.wall_time_s * 1e9 / r.periods : 0.0;
    std::printf("  per period: %.0f ns = firmware ISR (host build) %.0f ns + plant step (switching inverter, "
                "%s) %.0f ns + sensors, runner and metrics %.0f ns\n",
                per_period_ns, r.isr_ns_mean, sc.s("inverter.integrator").c_str(), r.plant_ns_mean,
                per_period_ns - r.isr_ns_mean - r.plant_ns_mean);
    float (*volatile sin_fn)(float) = sinf;  // two real calls, as an ISR would make
    float (*volatile cos_fn)(float) = cosf;
    const double t_fast = ns_per_call([](float x) { const mc_sincos_t r = mc_sincos(x); return r.s + r.c; });
    const double t_libm = ns_per_call([&](float x) { return sin_fn(x) + cos_fn(x); });
    std::printf("  mc_sincos: %.1f ns per call; libm sinf + cosf: %.1f ns (host)\n", t_fast, t_libm);
    return 0;
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "%s", kUsage);
        return 2;
    }
    const std::string cmd = argv[1];
    try {
        if (cmd == "run") return cmd_run(argc, argv, false);
        if (cmd == "check") return cmd_run(argc, argv, true);
        if (cmd == "bench") return cmd_bench(argc, argv);
        if (cmd == "image-config") return cmd_image_config(argc, argv);
        if (cmd == "keys") {
            std::printf("%s", mcsim::schema_markdown().c_str());
            return 0;
        }
        if (cmd == "params") {
            std::printf("%s", mcsim::params_markdown().c_str());
            return 0;
        }
        if (cmd == "faults") {
            std::printf("%s", mcsim::faults_markdown().c_str());
            return 0;
        }
        if (cmd == "-h" || cmd == "--help" || cmd == "help") {
            std::printf("%s", kUsage);
            return 0;
        }
        std::fprintf(stderr, "mcsim: unknown command '%s'\n%s", cmd.c_str(), kUsage);
        return 2;
    } catch (const mcsim::ScenarioError& e) {
        std::fprintf(stderr, "mcsim: error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mcsim: failed: %s\n", e.what());
        return 1;
    }
}
