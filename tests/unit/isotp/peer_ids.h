/* The ISO-TP ids of the test peers: the schema's physical base with the
 * default device and host addresses (landscape.proto IsotpId, NodeAddress).
 * Shared by isotp_peer, isotp_pty_peer and the VM tier's isotp_socketcan_echo. */
#ifndef LS_TEST_PEER_IDS_H
#define LS_TEST_PEER_IDS_H

#include <stdint.h>

#include "landscape.pb.h"

/* host -> device */
#define LS_PEER_RX_ID                                                                                                  \
    ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE | (uint32_t)ls_NodeAddress_DEFAULT_DEVICE_ADDRESS << 8 |                 \
     (uint32_t)ls_NodeAddress_DEFAULT_HOST_ADDRESS)
/* device -> host */
#define LS_PEER_TX_ID                                                                                                  \
    ((uint32_t)ls_IsotpId_ISOTP_PHYSICAL_BASE | (uint32_t)ls_NodeAddress_DEFAULT_HOST_ADDRESS << 8 |                   \
     (uint32_t)ls_NodeAddress_DEFAULT_DEVICE_ADDRESS)

#endif
