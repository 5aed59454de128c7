/* CAN hardware interface: classic CAN 2.0 frames (11- and 29-bit identifiers, up to 8 data bytes),
 * queued in both directions, never blocking: the CANopen stack (firmware/comms) calls it
 * from the background loop with bounded work per call. A port keeps its own queues (the host
 * port: rings the simulator fills and drains; a target: the controller's message RAM, e.g.
 * MCAN's TX FIFO and RX FIFO 0) and counts what it had to drop. Bit rate and acceptance filters
 * are the port's init, not part of this contract. */
#ifndef HAL_CAN_H
#define HAL_CAN_H
#include <stdbool.h>
#include <stdint.h>

typedef struct {
    uint32_t id;       /* 11 bits (ext false) or 29 bits (ext true) */
    bool ext;          /* extended (29-bit) identifier */
    bool rtr;          /* remote frame: no data, dlc says what is asked for */
    uint8_t dlc;       /* 0..8 */
    uint8_t data[8];
} hal_can_frame_t;

/* ISO 11898-1 fault confinement, as the controller reports it */
typedef enum {
    HAL_CAN_ERROR_ACTIVE = 0,   /* normal */
    HAL_CAN_ERROR_PASSIVE,      /* an error counter above 127: still sending, passive error flags */
    HAL_CAN_BUS_OFF             /* transmit error counter above 255: off the bus until recovered */
} hal_can_state_t;

typedef struct hal_can hal_can_t;   /* defined by the port */

/* A frame well formed for this interface: dlc <= 8, id within 11 / 29 bits. */
static inline bool hal_can_frame_valid(const hal_can_frame_t *f)
{
    return f->dlc <= 8u && f->id <= (f->ext ? 0x1FFFFFFFu : 0x7FFu);
}

/* Queue one frame for transmission. false, nothing queued: the frame is not valid, the TX queue
 * is full (counted by the port) or the controller is bus-off. */
bool hal_can_send(hal_can_t *can, const hal_can_frame_t *f);
/* Take the oldest received frame. false: none waiting. */
bool hal_can_receive(hal_can_t *can, hal_can_frame_t *f);
hal_can_state_t hal_can_state(const hal_can_t *can);
/* Ask a bus-off controller to rejoin (ISO 11898-1: after 128 x 11 recessive bits); a port that
 * recovers by itself may do nothing. Harmless in the other states. */
void hal_can_recover(hal_can_t *can);

#endif
