// Processor-in-the-loop: the peripherals of a target port, emulated at register level and backed
// by the plant. A port's model (dev_generic.cpp, dev_am263x.cpp) implements this interface; the
// engine (pil.cpp) maps its windows as MMIO in the emulated core and forwards every access.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mcsim::pil {

// What the plant and sensors give the peripherals at a PWM period boundary (counter zero).
struct PeriphInputs {
    uint16_t adc_i[3] = {0, 0, 0};   // phase a, b, c current channels [counts]
    uint16_t adc_vdc = 0;            // DC-link channel [counts]
    bool adc_overrun = false;        // the last EOC was not acknowledged in time (fault injection)
    uint32_t qep_count = 0;          // 0 .. counts_per_rev-1
    bool qep_index_seen = false;
    uint32_t qep_index_count = 0;
    uint32_t time_us = 0;            // free-running microseconds
};

// What the plant takes from the inverter for the next period.
struct PeriphOutputs {
    double duty[3] = {0.5, 0.5, 0.5};   // high-side on-fraction per phase, as latched
    bool enabled = false;               // false: all six switches off (safe state)
};

// A classic CAN frame on the bus side of a CAN controller model.
struct CanFrame {
    uint32_t id = 0;      // 11 or 29 bits
    bool ext = false, rtr = false;
    uint8_t dlc = 0;      // 0..8
    uint8_t data[8] = {};
};

struct MmioWindow {
    uint64_t base = 0, size = 0;        // size: a multiple of 4 KiB
    std::string name;
};

class Peripherals {
public:
    virtual ~Peripherals() = default;
    // Register windows (MMIO: every access comes to read()/write()).
    virtual std::vector<MmioWindow> windows() const = 0;
    // Plain memories of the part (flash, RAM, TCM, a memory-mapped flash window): mapped as RAM
    // by the engine, the ELF's segments loaded into them; an access outside these and the
    // windows stops the run with RunError.
    virtual std::vector<MmioWindow> memories() const = 0;
    // Access to those memories for a device that changes them (a flash controller's program and
    // erase commands). Called by the engine once after mapping.
    using MemWrite = std::function<void(uint32_t addr, const void* data, size_t n)>;
    using MemRead = std::function<void(uint32_t addr, void* data, size_t n)>;
    virtual void bind_memory(MemWrite write, MemRead read) { (void)write; (void)read; }
    // A load or store of 1, 2 or 4 bytes by the core. Unmapped offsets read 0 and ignore writes.
    virtual uint64_t read(uint64_t addr, unsigned size) = 0;
    virtual void write(uint64_t addr, unsigned size, uint64_t value) = 0;
    // Counter zero: the shadow compares become active, the ADC converts (EOC pending), the
    // encoder and time base advance to the given values.
    virtual void period_boundary(const PeriphInputs& in) = 0;
    // The duties in force for the coming period and the output enable.
    virtual PeriphOutputs outputs() const = 0;
    // What the next period_boundary will latch (the shadow compares; the enable as now): the
    // simulator's ADC model needs the coming period's duties before the boundary when the
    // conversion is delayed. Override it: the default is only right without shadowing.
    virtual PeriphOutputs pending_outputs() const { return outputs(); }
    // True when the control interrupt is enabled and pending (the ADC end-of-conversion routed to
    // the core as the firmware configured it); the engine then takes it.
    virtual bool irq_pending() const = 0;
    // Interrupt controller hand-off at IRQ entry (R5F/VIM: the handler address the IRQ vector code
    // reads; Cortex-M: unused, the engine reads the vector table). Return 0 if none.
    virtual uint32_t irq_vector() { return 0; }
    // PWM period and dead time as programmed [s] (for the report and the host-vs-PIL check).
    virtual double pwm_period_s() const = 0;
    virtual double dead_time_s() const = 0;
    // The compare resolution as programmed: duties are whole counts of a half period of
    // pwm_counts() (0: unknown), the compare value counting the high side's off-time when
    // pwm_off_time() (the host build mimics it: scenario keys inverter.pwm_counts / pwm_compare).
    virtual uint32_t pwm_counts() const { return 0; }
    virtual bool pwm_off_time() const { return false; }
    // The CAN controller's bus side, for a port that models one (else false): a frame the
    // firmware queued for transmission, and a frame received from the bus (into the firmware's
    // receive FIFO; false when it is full or the controller is not running).
    virtual bool can_supported() const { return false; }
    virtual bool can_take(CanFrame& f) { (void)f; return false; }
    virtual bool can_deliver(const CanFrame& f) { (void)f; return false; }
    // A board-side input pin driven from outside (a test, the bench): e.g. the AM263x's "nFAULT"
    // (the gate driver's fault line, high = released). False: the port has no such pin.
    virtual bool set_pin(const std::string& name, bool high) { (void)name; (void)high; return false; }
};

std::unique_ptr<Peripherals> make_generic_peripherals();   // hal/generic (Cortex-M4F image)
std::unique_ptr<Peripherals> make_am263x_peripherals();    // hal/am263x (Cortex-R5F image)

}  // namespace mcsim::pil
