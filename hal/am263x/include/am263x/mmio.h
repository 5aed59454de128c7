/* Register access of the AM263x port. Every driver reads and writes its registers through these
 * accessors, at an address formed from a base held in the port's structs (hal/am263x/port.h).
 *
 * Firmware build: plain volatile loads and stores of the register's width (the ePWM, eQEP and
 * ADC control registers are 16 bits wide and are accessed as such, as TI's SDK does).
 * Host test build (AM263X_MMIO_HOOKS defined): every access calls am263x_mmio_read/_write, which
 * the test provides: a RAM-array fake that emulates the few registers with behaviour (the QSPI
 * controller in the NVM test), or the processor-in-the-loop register model (test_am263x_pil). */
#ifndef AM263X_MMIO_H
#define AM263X_MMIO_H
#include <stdint.h>

#if defined(AM263X_MMIO_HOOKS)
uint32_t am263x_mmio_read(uintptr_t addr, unsigned size);
void am263x_mmio_write(uintptr_t addr, unsigned size, uint32_t value);

static inline uint32_t am263x_rd32(uintptr_t a) { return am263x_mmio_read(a, 4u); }
static inline uint16_t am263x_rd16(uintptr_t a) { return (uint16_t)am263x_mmio_read(a, 2u); }
static inline uint8_t am263x_rd8(uintptr_t a) { return (uint8_t)am263x_mmio_read(a, 1u); }
static inline void am263x_wr32(uintptr_t a, uint32_t v) { am263x_mmio_write(a, 4u, v); }
static inline void am263x_wr16(uintptr_t a, uint16_t v) { am263x_mmio_write(a, 2u, v); }
#else
static inline uint32_t am263x_rd32(uintptr_t a) { return *(const volatile uint32_t *)a; }
static inline uint16_t am263x_rd16(uintptr_t a) { return *(const volatile uint16_t *)a; }
static inline uint8_t am263x_rd8(uintptr_t a) { return *(const volatile uint8_t *)a; }
static inline void am263x_wr32(uintptr_t a, uint32_t v) { *(volatile uint32_t *)a = v; }
static inline void am263x_wr16(uintptr_t a, uint16_t v) { *(volatile uint16_t *)a = v; }
#endif

#endif
