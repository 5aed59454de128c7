// ADC and quadrature-encoder models, see sim/include/mcsim/sensors.hpp.
#include "mcsim/sensors.hpp"

#include <cmath>
#include <stdexcept>

namespace mcsim {

namespace {
constexpr double kTwoPi = 6.28318530717958647692;

// round-half-away-from-zero, clamped to the ADC rails [0, max_count]; the comparisons come
// before any conversion, so no value converts to an integer out of range (UB): -inf and values
// below the rail give 0, +inf and values above give max_count. NaN (a diverged plant) gives 0,
// the low rail, on purpose: a real ADC reads a rail when its input is out of range, and for the
// firmware that is a full-scale negative phase current (over-current trip) or Vdc = 0
// (under-voltage trip), i.e. a fault and a stop rather than plausible-looking samples.
uint16_t to_counts(double x, double max_count) {
    if (!(x >= 0.5)) return 0;  // also NaN
    if (x >= max_count) return static_cast<uint16_t>(max_count);
    return static_cast<uint16_t>(x + 0.5);  // truncation of a positive value: the same as round
}
}  // namespace

Sensors::Sensors(const AdcConfig& adc, const EncoderConfig& enc, uint64_t seed)
    : adc_(adc), enc_(enc), n01_(seed) {
    if (adc.bits < 2 || adc.bits > 16) throw std::invalid_argument("AdcConfig.bits must be 2..16");
    if (!(adc.i_full_scale > 0.0) || !(adc.vdc_full_scale > 0.0))
        throw std::invalid_argument("AdcConfig full scales must be > 0");
    if (enc.lines < 1) throw std::invalid_argument("EncoderConfig.lines must be >= 1");
    max_count_ = std::ldexp(1.0, adc_.bits) - 1.0;
    amps_per_count_ = 2.0 * adc_.i_full_scale / max_count_;
    offset_counts_ = std::ldexp(1.0, adc_.bits - 1);
    volts_per_count_ = adc_.vdc_full_scale / max_count_;
}

double Sensors::amps_per_count() const { return amps_per_count_; }
double Sensors::offset_counts() const { return offset_counts_; }
double Sensors::volts_per_count() const { return volts_per_count_; }

AdcSample Sensors::sample_adc(const Plant& p) { return sample_adc(p.i_abc(), p.config().inverter.vdc, p.time()); }

AdcSample Sensors::sample_adc(const Plant& p, double vdc, double Ts, const std::array<double, 3>& duty,
                              bool outputs_enabled) {
    const std::array<double, 3> i =
        adc_.delay_s > 0.0 ? p.i_abc_ahead(adc_.delay_s, Ts, duty, outputs_enabled) : p.i_abc();
    return sample_adc(i, vdc, p.time());
}

AdcSample Sensors::sample_adc(const std::array<double, 3>& i, double vdc, double t) {
    AdcSample s{};
    const double max_count = max_count_;
    const double inv_apc = 1.0 / amps_per_count_, mid = offset_counts_;
    const SensorFaults& f = faults_;
    const double drift_t = t > f.i_offset_drift_from_s ? t - f.i_offset_drift_from_s : 0.0;
    const int stuck = f.i_stuck_phase >= 0 && t >= f.i_stuck_from_s ? f.i_stuck_phase : -1;
    // Draw order is fixed (a, b, c, vdc) so a seed reproduces a run exactly (also with faults:
    // a stuck channel still draws its noise).
    for (int k = 0; k < 3; ++k) {
        double meas = i[k] * (1.0 + adc_.gain_err[k]) + adc_.offset_err[k] + adc_.i_noise_rms * n01_();
        if (f.i_offset_drift_a_per_s[k] != 0.0) meas += f.i_offset_drift_a_per_s[k] * drift_t;
        if (k == stuck) meas = f.i_stuck_a;
        s.i[k] = to_counts(meas * inv_apc + mid, max_count);
    }
    s.vdc = to_counts(vdc * (1.0 + adc_.vdc_noise_rel * n01_()) / volts_per_count_, max_count);
    return s;
}

QepSample Sensors::sample_qep(const Plant& p) {
    if (faults_.encoder_loss_from_s >= 0.0 && p.time() >= faults_.encoder_loss_from_s) {
        // The counter stops: the last sample before the loss, or (lost from the start) the
        // position at the first sample.
        if (!qep_frozen_ && !have_prev_) {
            qep_frozen_ = true;
            faults_.encoder_loss_from_s = -1.0;  // take this one sample normally
            qep_last_ = sample_qep(p);
            faults_.encoder_loss_from_s = p.time();
        }
        qep_frozen_ = true;
        return qep_last_;
    }
    const double n = 4.0 * enc_.lines;
    double rev = (p.theta_m() - enc_.offset_rad) / kTwoPi;
    // A diverged plant (NaN or inf angle): the counter holds its last position (a quadrature
    // counter only ever moves by edges), and the conversion below stays defined.
    if (!std::isfinite(rev)) rev = have_prev_ ? prev_rev_ : 0.0;
    double c = std::fmod(std::floor(rev * n), n);
    if (c < 0) c += n;
    if (!(c >= 0.0 && c < n)) c = 0.0;  // rev * n overflowed to inf (|theta_m| ~ 1e300): no position left
    // The index mark sits at rev = integer: it was passed if an integer lies in (prev, rev]
    // (forwards) or in (rev, prev] (backwards). Sampling is assumed faster than half a turn.
    if (have_prev_ && !index_seen_) {
        if (std::floor(rev) > std::floor(prev_rev_)) {
            index_seen_ = true;
            index_count_ = 0;
        } else if (std::floor(rev) < std::floor(prev_rev_)) {
            index_seen_ = true;
            index_count_ = static_cast<uint32_t>(n - 1);
        }
    }
    have_prev_ = true;
    prev_rev_ = rev;
    qep_last_ = QepSample{static_cast<uint32_t>(c), index_seen_, index_count_};
    return qep_last_;
}

}  // namespace mcsim
