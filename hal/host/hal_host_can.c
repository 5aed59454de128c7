/* Host port: CAN as two rings (hal/can.h, hal_host/host.h). */
#include "hal_host/host.h"

void hal_host_can_init(hal_can_t *can)
{
    *can = (hal_can_t){.state = HAL_CAN_ERROR_ACTIVE};
}

/* a valid frame into a ring; a full ring refuses it and counts it */
static bool push(hal_can_frame_t *ring, uint32_t head, uint32_t *count, uint32_t *dropped, const hal_can_frame_t *f)
{
    if (!hal_can_frame_valid(f)) {
        return false;
    }
    if (*count >= HAL_HOST_CAN_QUEUE) {
        (*dropped)++;
        return false;
    }
    ring[(head + *count) % HAL_HOST_CAN_QUEUE] = *f;
    (*count)++;
    return true;
}

static bool pop(const hal_can_frame_t *ring, uint32_t *head, uint32_t *count, hal_can_frame_t *f)
{
    if (*count == 0u) {
        return false;
    }
    *f = ring[*head];
    *head = (*head + 1u) % HAL_HOST_CAN_QUEUE;
    (*count)--;
    return true;
}

bool hal_can_send(hal_can_t *can, const hal_can_frame_t *f)
{
    return can->state != HAL_CAN_BUS_OFF && push(can->tx, can->tx_head, &can->tx_count, &can->tx_dropped, f);
}

bool hal_can_receive(hal_can_t *can, hal_can_frame_t *f)
{
    return pop(can->rx, &can->rx_head, &can->rx_count, f);
}

hal_can_state_t hal_can_state(const hal_can_t *can)
{
    return can->state;
}

void hal_can_recover(hal_can_t *can)
{
    if (can->state == HAL_CAN_BUS_OFF) {
        can->recoveries++;
        can->state = HAL_CAN_ERROR_ACTIVE;   /* the host's bus is quiet at once */
    }
}

bool hal_host_can_deliver(hal_can_t *can, const hal_can_frame_t *f)
{
    return push(can->rx, can->rx_head, &can->rx_count, &can->rx_dropped, f);
}

bool hal_host_can_take(hal_can_t *can, hal_can_frame_t *f)
{
    return pop(can->tx, &can->tx_head, &can->tx_count, f);
}

void hal_host_can_set_state(hal_can_t *can, hal_can_state_t s)
{
    can->state = s;
}
