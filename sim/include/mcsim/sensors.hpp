// Sensors sampled at the PWM period boundary (ADC at PWM centre of V000): phase currents through
// a 12-bit ADC with gain/offset error and white noise, Vdc with noise, quadrature encoder.
#pragma once
#include <cmath>
#include <cstdint>
#include "mcsim/plant.hpp"

namespace mcsim {

// Standard normal draws for the sensor noise: xoshiro256** (seeded through splitmix64) and the
// Marsaglia polar method, which yields two draws per logarithm. Written out because the
// mt19937_64 + std::normal_distribution pair cost more per PWM period than the firmware's ISR.
class NormalRng {
public:
    explicit NormalRng(uint64_t seed) {
        for (uint64_t& w : s_) {  // splitmix64: any seed, including 0, gives a non-zero state
            seed += 0x9e3779b97f4a7c15ULL;
            uint64_t z = seed;
            z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
            z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
            w = z ^ (z >> 31);
        }
    }
    double operator()() {
        if (have_spare_) {
            have_spare_ = false;
            return spare_;
        }
        double u, v, r2;
        do {
            u = 2.0 * uniform() - 1.0;
            v = 2.0 * uniform() - 1.0;
            r2 = u * u + v * v;
        } while (r2 >= 1.0 || r2 == 0.0);
        const double f = std::sqrt(-2.0 * std::log(r2) / r2);
        spare_ = v * f;
        have_spare_ = true;
        return u * f;
    }

private:
    static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    uint64_t next() {
        const uint64_t r = rotl(s_[1] * 5, 7) * 9, t = s_[1] << 17;
        s_[2] ^= s_[0];
        s_[3] ^= s_[1];
        s_[1] ^= s_[2];
        s_[0] ^= s_[3];
        s_[2] ^= t;
        s_[3] = rotl(s_[3], 45);
        return r;
    }
    double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)

    uint64_t s_[4];
    double spare_ = 0.0;
    bool have_spare_ = false;
};

struct AdcConfig {
    int bits = 12;
    double i_full_scale = 25.0;     // [A] counts span -fs..+fs
    double i_noise_rms = 0.02;      // [A]
    double gain_err[3] = {0, 0, 0}; // relative, per phase
    double offset_err[3] = {0, 0, 0}; // [A], per phase
    double vdc_full_scale = 500.0;  // [V] counts span 0..fs
    double vdc_noise_rel = 0.005;   // rms relative to the value
    // Conversion delay: the currents are sampled this long after the period boundary (the PWM
    // centre), through Plant::i_abc_ahead (first order in the delay). 0: at the boundary.
    double delay_s = 0.0;
};

// Injected sensor faults (scenario keys faults.*; times from the start of the run, plant time).
struct SensorFaults {
    // Current channel stuck: from i_stuck_from_s on, channel i_stuck_phase (0..2; -1 none) reads
    // i_stuck_a, converted with the nominal scale (no gain, offset or noise; clamped to the rails).
    int i_stuck_phase = -1;
    double i_stuck_from_s = 0.0;
    double i_stuck_a = 0.0;
    // Offset drift: from i_offset_drift_from_s on, channel k's offset grows by
    // i_offset_drift_a_per_s[k] * (t - from) [A] on top of AdcConfig::offset_err.
    double i_offset_drift_a_per_s[3] = {0, 0, 0};
    double i_offset_drift_from_s = 0.0;
    // Encoder loss: from encoder_loss_from_s on (< 0: never) the counter no longer counts: every
    // sample repeats the last one taken before that time (no new index either).
    double encoder_loss_from_s = -1.0;
};

struct EncoderConfig {
    int lines = 2500;               // per mechanical revolution; counts = 4 * lines
    double offset_rad = 0.0;        // mechanical angle at which the count is 0 (and index)
};

struct AdcSample { uint16_t i[3]; uint16_t vdc; };
// count in [0, 4*lines); index_seen latches at the first pass of the index (theta_m = offset mod
// 2 pi) between two samples; index_count is the count the counter held at that index edge
// (0 when passed forwards, 4*lines-1 backwards), as an eQEP index latch would capture it.
struct QepSample { uint32_t count; bool index_seen; uint32_t index_count; };

class Sensors {
public:
    Sensors(const AdcConfig& adc, const EncoderConfig& enc, uint64_t seed);
    // At the plant's boundary: the currents p.i_abc(), Vdc = p.config().inverter.vdc, no delay.
    AdcSample sample_adc(const Plant& p);
    // The runner's: Vdc given (the DC link's value at this instant), the currents AdcConfig::delay_s
    // after the boundary of a period of length Ts that the duties (latched now) will switch.
    AdcSample sample_adc(const Plant& p, double vdc, double Ts, const std::array<double, 3>& duty,
                         bool outputs_enabled);
    // The conversion itself: true phase currents, Vdc and the time t (for the faults).
    AdcSample sample_adc(const std::array<double, 3>& i_abc, double vdc, double t);
    QepSample sample_qep(const Plant& p);
    void set_faults(const SensorFaults& f) { faults_ = f; }
    const SensorFaults& faults() const { return faults_; }
    // Phase-current counts: round(i_meas/(2 fs) * (2^bits - 1) + 2^(bits-1)), clamped, where
    // i_meas = i (1 + gain_err) + offset_err + noise; Vdc counts: round(v (1 + rel noise)/fs *
    // (2^bits - 1)). Call right after Plant::step_period: the plant time is then the period
    // boundary, the centre of V000, where the sample equals the period average in steady state.
    // Firmware-side scaling that matches this ADC (nominal, without the errors):
    // i = (count - offset_counts) * amps_per_count, vdc = count * volts_per_count.
    double amps_per_count() const;
    double offset_counts() const;
    double volts_per_count() const;
    const AdcConfig& adc() const { return adc_; }
    const EncoderConfig& encoder() const { return enc_; }

private:
    AdcConfig adc_;
    EncoderConfig enc_;
    SensorFaults faults_;
    bool qep_frozen_ = false;
    QepSample qep_last_{0, false, 0};
    NormalRng n01_;
    double max_count_ = 0, amps_per_count_ = 0, offset_counts_ = 0, volts_per_count_ = 0;
    bool index_seen_ = false;
    uint32_t index_count_ = 0;
    bool have_prev_ = false;
    double prev_rev_ = 0.0;         // (theta_m - offset)/(2 pi) at the previous QEP sample
};

}  // namespace mcsim
