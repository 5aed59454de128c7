#include "metrics.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace {
constexpr double kPiM = 3.14159265358979323846;
}

namespace mcsim {

std::string json_number(double v)
{
    if (!std::isfinite(v)) return "null";
    std::ostringstream os;
    os.precision(6);
    os << v;
    return os.str();
}

std::string json_string(const std::string& s)
{
    static const char* const kHex = "0123456789abcdef";
    std::string o;
    o.reserve(s.size() + 2);
    o += '"';
    const size_t n = s.size();
    for (size_t k = 0; k < n;) {
        const unsigned char c = static_cast<unsigned char>(s[k]);
        if (c < 0x80) {
            switch (c) {
            case '"': o += "\\\""; break;
            case '\\': o += "\\\\"; break;
            case '\b': o += "\\b"; break;
            case '\f': o += "\\f"; break;
            case '\n': o += "\\n"; break;
            case '\r': o += "\\r"; break;
            case '\t': o += "\\t"; break;
            default:
                if (c < 0x20 || c == 0x7f) {
                    o += "\\u00";
                    o += kHex[c >> 4];
                    o += kHex[c & 15];
                } else {
                    o += static_cast<char>(c);
                }
            }
            ++k;
            continue;
        }
        // Multi-byte UTF-8: copy a well-formed sequence, replace each byte of anything else by
        // U+FFFD.
        const size_t len = utf8_sequence_len(s, k);
        const bool ok = len > 1;
        if (ok) {
            o.append(s, k, len);
            k += len;
        } else {
            o += "\\ufffd";
            ++k;
        }
    }
    o += '"';
    return o;
}

std::string json_string_array(const std::vector<std::string>& v)
{
    std::string o = "[";
    for (size_t k = 0; k < v.size(); ++k) o += (k ? ", " : "") + json_string(v[k]);
    return o + "]";
}

Metrics::Metrics(const Scenario& sc)
    : start_(sc.f("metrics.start_s")),
      settle_from_(sc.f("metrics.settle_from_s")),
      band_(sc.f("metrics.settle_band")),
      settle_signal_(sc.s("metrics.settle_signal")),
      windows_(sc.windows()),
      win_acc_(sc.windows().size())
{
}

void Metrics::acc_add(Acc& a, const Sample& s) const
{
    a.n += 1;
    a.i_peak = std::max(a.i_peak, s.i_peak);
    a.speed_sum += s.speed_rpm;
    a.tq_all_sum += s.torque;
    if (!s.running) return;
    a.run_n += 1;
    if (s.if_open) {
        a.if_n += 1;   // the I/f frame's angle is no estimate: its load angle is not an error
    } else {
        a.err_n += 1;
        a.err_sum += s.angle_err_deg;
        a.err_absmax = std::max(a.err_absmax, std::fabs(s.angle_err_deg));
    }
    a.id_sum += s.id;
    a.iq_sum += s.iq;
    a.tq_sum += s.torque;
    if (std::isfinite(s.speed_ref_rpm)) {
        const double e = s.speed_rpm - s.speed_ref_rpm;
        a.sp_n += 1;
        a.sp_sq += e * e;
        a.sp_max_abs = std::max(a.sp_max_abs, std::fabs(e));
        a.ref_sum += s.speed_ref_rpm;
    }
}

static double wrap180(double deg)
{
    double x = std::fmod(deg + 180.0, 360.0);
    if (x < 0) x += 360.0;
    return x - 180.0;
}

void Metrics::add_startup(const Sample& s)
{
    constexpr int kIdle = 0, kInit = 4, kRun = 2, kStep3 = 3;
    if (!std::isfinite(t_enable_) && s.state != kIdle) {
        t_enable_ = s.t;
        th0_ = s.theta_e_unwrapped;
    }
    if (!std::isfinite(t_enable_)) return;
    constexpr int kFault = 3, kReaction = 5;   // the reason is latched from the reaction on
    if ((s.state == kFault || s.state == kReaction) && !std::isfinite(t_fault_)) t_fault_ = s.t;
    if (s.state == kRun && !std::isfinite(t_first_run_)) t_first_run_ = s.t;
    // the rotor must not turn against the intended direction (electrical degrees)
    reverse_max_ = std::max(reverse_max_, -s.direction * (s.theta_e_unwrapped - th0_) * 180.0 / kPiM);
    // Step I + II from Step I's start: the flying-start catch's probe (init step 4) before it
    // is timed separately
    constexpr int kStep1 = 1, kCatch = 4;
    if (s.state == kInit && s.init_step == kStep1 && !std::isfinite(t_init_)) t_init_ = s.t;
    if (s.state == kInit && s.init_step == kCatch && !std::isfinite(t_catch_)) t_catch_ = s.t;
    if (std::isfinite(t_catch_) && !std::isfinite(t_catch_end_) && !(s.state == kInit && s.init_step == kCatch))
        t_catch_end_ = s.t;
    if (s.state == kInit) was_init_ = true;
    if (s.state == kInit && s.init_step == kStep3 && !std::isfinite(t_step3_)) {
        t_step3_ = s.t;
        step12_err_ = wrap180(s.theta2_deg - s.theta_true_deg);
        step1_err_ = wrap180(2.0 * (s.theta1_deg - s.theta_true_deg)) / 2.0;   // modulo 180 deg
    }
    if (was_init_ && s.state == kRun && !std::isfinite(t_run_)) {
        t_run_ = s.t;
        init_err_ = s.angle_err_any;
    }
    if (s.state == kRun && std::isfinite(t_run_) && s.t < t_run_ + 0.02 && std::isfinite(s.angle_err_any)) {
        post_sum_ += s.angle_err_any;
        post_n_ += 1;
    }
    // locked: in RUN with the angle within 10 deg from then on (the flying start's criterion)
    if (!(s.state == kRun && std::fabs(s.angle_err_any) <= 10.0)) t_unlocked_ = s.t;
    i_peak_enable_ = std::max(i_peak_enable_, s.i_peak);
    // "enable to < 1 deg": the last sample at or above 1 deg in Step III and the first 20 ms of RUN
    const bool watch = (s.state == kInit && s.init_step == kStep3) ||
                       (s.state == kRun && std::isfinite(t_run_) && s.t < t_run_ + 0.02);
    if (watch && !(std::fabs(s.angle_err_any) < 1.0)) t_last_bad_ = s.t;
}

void Metrics::add(const Sample& s)
{
    last_t_ = s.t;
    ts_ = s.ts;
    add_startup(s);
    if (s.iters >= 0) {
        iter_sum_ += s.iters;
        iter_n_ += 1;
        iter_max_ = std::max(iter_max_, s.iters);
    }
    if_seen_ = if_seen_ || s.if_on;
    if (s.running && s.if_open) if_open_s_ += s.ts;
    if (s.t >= start_) {
        i_peak_ = std::max(i_peak_, s.i_peak);
        if (s.running) angle_err_max_ = std::max(angle_err_max_, std::fabs(s.angle_err_deg));
    }
    for (size_t w = 0; w < windows_.size(); ++w) {
        if (s.t >= windows_[w].from_s && s.t < windows_[w].to_s) {
            acc_add(win_acc_[w], s);
            acc_add(steady_, s);
        }
    }
    if (s.t >= settle_from_) {
        double e = NAN;
        if (settle_signal_ == "speed") e = s.speed_rpm - s.speed_ref_rpm;
        else if (settle_signal_ == "angle") e = s.angle_err_deg;
        else if (settle_signal_ == "iq") e = s.iq - s.iq_ref;
        any_settle_sample_ = true;
        if (s.running && std::isfinite(e)) {
            const double ae = std::fabs(e);
            if (!std::isfinite(e0_)) e0_ = ae;
            if (!std::isfinite(t90_) && ae <= 0.9 * e0_) t90_ = s.t;
            if (!std::isfinite(t10_) && ae <= 0.1 * e0_) t10_ = s.t;
        }
        // a sample not running, or without a reference, counts as out of band
        if (!s.running || !std::isfinite(e) || std::fabs(e) > band_) last_out_of_band_ = s.t;
    }
}

std::string Metrics::json(const std::vector<std::string>& faults, const std::string& final_state,
                          const std::vector<std::pair<std::string, std::string>>& extra) const
{
    auto mean = [](double sum, double n) { return n > 0 ? sum / n : NAN; };
    auto pct = [](const Acc& a) {
        const double ref = a.sp_n > 0 ? std::fabs(a.ref_sum / a.sp_n) : 0.0;
        return ref > 1.0 ? 100.0 * a.sp_max_abs / ref : NAN;
    };
    double settling = NAN;
    if (any_settle_sample_) {
        if (last_out_of_band_ < 0) settling = 0.0;
        else if (last_out_of_band_ < last_t_) settling = last_out_of_band_ - settle_from_;
    }
    std::ostringstream os;
    os << "{\n";
    os << "  \"angle_err_max_deg\": " << json_number(angle_err_max_) << ",\n";
    os << "  \"angle_err_steady_mean_deg\": " << json_number(mean(steady_.err_sum, steady_.err_n)) << ",\n";
    os << "  \"angle_err_steady_max_deg\": " << json_number(steady_.err_n > 0 ? steady_.err_absmax : NAN) << ",\n";
    if (if_seen_) {
        os << "  \"if_open_s\": " << json_number(if_open_s_) << ",\n";
        os << "  \"if_open_steady_share\": " << json_number(steady_.run_n > 0 ? steady_.if_n / steady_.run_n : NAN) << ",\n";
    }
    os << "  \"speed_err_steady_rms_rpm\": " << json_number(steady_.sp_n > 0 ? std::sqrt(steady_.sp_sq / steady_.sp_n) : NAN) << ",\n";
    os << "  \"speed_err_steady_max_rpm\": " << json_number(steady_.sp_n > 0 ? steady_.sp_max_abs : NAN) << ",\n";
    // Relative error is per window (each against its own reference); the headline is the worst.
    double pct_max = NAN;
    for (const auto& a : win_acc_) {
        const double v = pct(a);
        if (std::isfinite(v)) pct_max = std::isfinite(pct_max) ? std::max(pct_max, v) : v;
    }
    os << "  \"speed_err_steady_max_pct\": " << json_number(pct_max) << ",\n";
    os << "  \"settling_time_s\": " << json_number(settling) << ",\n";
    os << "  \"rise_time_s\": " << json_number(std::isfinite(t90_) && std::isfinite(t10_) ? t10_ - t90_ : NAN) << ",\n";
    os << "  \"current_peak_a\": " << json_number(i_peak_) << ",\n";
    const bool init = std::isfinite(t_step3_);
    os << "  \"step12_time_s\": " << json_number(init ? t_step3_ - t_enable_ : NAN) << ",\n";
    os << "  \"step12_duration_s\": " << json_number(init ? t_step3_ - t_init_ : NAN) << ",\n";
    os << "  \"catch_duration_s\": " << json_number(t_catch_end_ - t_catch_) << ",\n";
    // enable -> in RUN within 10 deg for good (null: never, or not at the end)
    const bool locked = std::isfinite(t_enable_) && (!std::isfinite(t_unlocked_) || t_unlocked_ < last_t_);
    os << "  \"lock_time_s\": "
       << json_number(locked ? (std::isfinite(t_unlocked_) ? t_unlocked_ + ts_ : t_enable_) - t_enable_ : NAN) << ",\n";
    os << "  \"current_peak_from_enable_a\": " << json_number(i_peak_enable_) << ",\n";
    os << "  \"step1_err_deg\": " << json_number(step1_err_) << ",\n";
    os << "  \"step12_err_deg\": " << json_number(step12_err_) << ",\n";
    os << "  \"polarity_correct\": " << (init ? (std::fabs(step12_err_) < 90.0 ? "true" : "false") : "null") << ",\n";
    os << "  \"init_pos_err_deg\": " << json_number(init_err_) << ",\n";
    os << "  \"init_pos_err_mean_deg\": " << json_number(post_n_ > 0 ? post_sum_ / post_n_ : NAN) << ",\n";
    os << "  \"init_pos_time_s\": "
       << json_number(init && std::isfinite(t_run_) ? (std::isfinite(t_last_bad_) ? t_last_bad_ + ts_ : t_step3_) - t_enable_ : NAN)
       << ",\n";
    os << "  \"reverse_angle_max_deg\": " << json_number(std::isfinite(t_enable_) ? reverse_max_ : NAN) << ",\n";
    os << "  \"newton_iter_mean\": " << json_number(iter_n_ > 0 ? iter_sum_ / iter_n_ : NAN) << ",\n";
    os << "  \"newton_iter_max\": " << json_number(iter_max_ >= 0 ? iter_max_ : NAN) << ",\n";
    for (const auto& [k, v] : extra) os << "  " << json_string(k) << ": " << v << ",\n";
    os << "  \"final_state\": " << json_string(final_state) << ",\n";
    // when the drive first went to FAULT, and how long after it first ran (the detection time
    // of a fault that appears at the start of RUN)
    os << "  \"fault_time_s\": " << json_number(t_fault_) << ",\n";
    os << "  \"fault_after_run_s\": " << json_number(t_fault_ - t_first_run_) << ",\n";
    os << "  \"faults\": [";
    for (size_t k = 0; k < faults.size(); ++k) os << (k ? ", " : "") << json_string(faults[k]);
    os << "],\n";
    os << "  \"windows\": {";
    for (size_t w = 0; w < windows_.size(); ++w) {
        const Acc& a = win_acc_[w];
        os << (w ? "," : "") << "\n    " << json_string(windows_[w].name) << ": {"
           << "\"from_s\": " << json_number(windows_[w].from_s)
           << ", \"to_s\": " << json_number(windows_[w].to_s)
           << ", \"angle_err_mean_deg\": " << json_number(mean(a.err_sum, a.err_n))
           << ", \"angle_err_max_deg\": " << json_number(a.err_n > 0 ? a.err_absmax : NAN)
           << ", \"speed_err_rms_rpm\": " << json_number(a.sp_n > 0 ? std::sqrt(a.sp_sq / a.sp_n) : NAN)
           << ", \"speed_err_max_rpm\": " << json_number(a.sp_n > 0 ? a.sp_max_abs : NAN)
           << ", \"speed_err_max_pct\": " << json_number(pct(a))
           << ", \"speed_mean_rpm\": " << json_number(mean(a.speed_sum, a.n))
           << ", \"speed_ref_mean_rpm\": " << json_number(mean(a.ref_sum, a.sp_n))
           << ", \"id_mean_a\": " << json_number(mean(a.id_sum, a.run_n))
           << ", \"iq_mean_a\": " << json_number(mean(a.iq_sum, a.run_n))
           << ", \"torque_mean_nm\": " << json_number(mean(a.tq_sum, a.run_n))
           << ", \"shaft_torque_mean_nm\": " << json_number(mean(a.tq_all_sum, a.n))
           << ", \"current_peak_a\": " << json_number(a.i_peak)
           << ", \"samples\": " << json_number(a.n);
        if (if_seen_) os << ", \"if_open_share\": " << json_number(a.run_n > 0 ? a.if_n / a.run_n : NAN);
        os << "}";
    }
    os << (windows_.empty() ? "" : "\n  ") << "}\n}\n";
    return os.str();
}

}  // namespace mcsim
