// Sensors sampled at the PWM period boundary (ADC at PWM centre of V000): phase currents through
// a 12-bit ADC with gain/offset error and white noise, Vdc with noise, quadrature encoder.
#pragma once
#include <cstdint>
#include <random>
#include "mcsim/plant.hpp"

namespace mcsim {

struct AdcConfig {
    int bits = 12;
    double i_full_scale = 25.0;     // [A] counts span -fs..+fs
    double i_noise_rms = 0.02;      // [A]
    double gain_err[3] = {0, 0, 0}; // relative, per phase
    double offset_err[3] = {0, 0, 0}; // [A], per phase
    double vdc_full_scale = 500.0;  // [V] counts span 0..fs
    double vdc_noise_rel = 0.005;   // rms relative to the value
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
    AdcSample sample_adc(const Plant& p);
    QepSample sample_qep(const Plant& p);
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
    std::mt19937_64 rng_;
    std::normal_distribution<double> n01_{0.0, 1.0};
    bool index_seen_ = false;
    uint32_t index_count_ = 0;
    bool have_prev_ = false;
    double prev_rev_ = 0.0;         // (theta_m - offset)/(2 pi) at the previous QEP sample
};

}  // namespace mcsim
