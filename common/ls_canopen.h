/* CANopen: the constants of CiA 301 (communication profile) and CiA 402
 * (drives and motion control) that the drive master (firmware/canopen), the
 * simulated drives (hal/sim/drives) and their tests share. One home: no
 * other file spells a COB-ID base, a command specifier, an abort code or a
 * statusword mask as a number.
 *
 * Names follow the standards (CiA 301 v4.2, CiA 402 part 2). Header and
 * ls_canopen.c only: includes nothing from hal/ or firmware/, allocates
 * nothing, reads no clock. */
#ifndef LS_CANOPEN_H
#define LS_CANOPEN_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Node ids and COB-IDs (11-bit identifiers, predefined connection set) */

#define LS_CO_NODE_MIN 1u
#define LS_CO_NODE_MAX 127u

#define LS_CO_COB_NMT 0x000u       /* NMT command: [command specifier, node id or 0 = all] */
#define LS_CO_COB_SYNC 0x080u      /* SYNC: no data (or one counter byte, 0x1019) */
#define LS_CO_COB_EMCY 0x080u      /* + node id: EMCY, 8 bytes */
#define LS_CO_COB_TPDO1 0x180u     /* + node id; TPDOn at 0x180 + 0x100 (n - 1) */
#define LS_CO_COB_RPDO1 0x200u     /* + node id; RPDOn at 0x200 + 0x100 (n - 1) */
#define LS_CO_COB_SDO_TX 0x580u    /* + node id: server -> client (the drive answers) */
#define LS_CO_COB_SDO_RX 0x600u    /* + node id: client -> server (the master asks) */
#define LS_CO_COB_HEARTBEAT 0x700u /* + node id: NMT error control, one state byte */
#define LS_CO_COB_MASK 0x7FFu      /* the 11 identifier bits of a COB-ID object's value */

/* The predefined COB-ID of PDO n (1..4) of `node`. */
#define LS_CO_COB_TPDO(n, node) (LS_CO_COB_TPDO1 + 0x100u * ((uint32_t)(n)-1u) + (uint32_t)(node))
#define LS_CO_COB_RPDO(n, node) (LS_CO_COB_RPDO1 + 0x100u * ((uint32_t)(n)-1u) + (uint32_t)(node))

/* COB-ID object values (0x1400-0x15FF:01, 0x1800-0x19FF:01, 0x1005, 0x1014). */
#define LS_CO_COBID_INVALID 0x80000000u  /* bit 31: the PDO (or EMCY) does not exist / is disabled */
#define LS_CO_COBID_NO_RTR 0x40000000u   /* bit 30: TPDO: no RTR allowed; RPDO: reserved */
#define LS_CO_COBID_FRAME 0x20000000u    /* bit 29: 29-bit identifier */
#define LS_CO_COBID_SYNC_GEN 0x40000000u /* 0x1005 bit 30: this node produces the SYNC */
#define LS_CO_COBID_RESERVED 0x1FFFF800u /* bits 11-28: zero for an 11-bit COB-ID */

/* Consumer heartbeat time entries (0x1016:n). */
#define LS_CO_HB_CONSUMER_NODE_SHIFT 16u
#define LS_CO_HB_CONSUMER_NODE_MASK 0x00FF0000u
#define LS_CO_HB_CONSUMER_TIME_MASK 0x0000FFFFu /* ms; 0: the entry is off */
#define LS_CO_HB_CONSUMER_RESERVED 0xFF000000u

/* Error behaviour 0x1029:01: the NMT state a communication error leads to. */
#define LS_CO_ERR_BEHAVIOUR_PREOP 0u     /* to PRE-OPERATIONAL (when OPERATIONAL) */
#define LS_CO_ERR_BEHAVIOUR_NO_CHANGE 1u /* stay */
#define LS_CO_ERR_BEHAVIOUR_STOPPED 2u   /* to STOPPED */

/* ---- NMT */

/* Command specifiers of the NMT command frame (byte 0). */
#define LS_CO_NMT_START 0x01u       /* start remote node: -> OPERATIONAL */
#define LS_CO_NMT_STOP 0x02u        /* stop remote node: -> STOPPED */
#define LS_CO_NMT_ENTER_PREOP 0x80u /* -> PRE-OPERATIONAL */
#define LS_CO_NMT_RESET_NODE 0x81u  /* reset application and communication */
#define LS_CO_NMT_RESET_COMM 0x82u  /* reset communication */
#define LS_CO_NMT_ALL_NODES 0x00u   /* byte 1: every node */

/* NMT states as a heartbeat carries them (bit 7, the guarding toggle, is 0 in heartbeats). */
#define LS_CO_NMT_BOOTUP 0x00u
#define LS_CO_NMT_STOPPED 0x04u
#define LS_CO_NMT_OPERATIONAL 0x05u
#define LS_CO_NMT_PREOPERATIONAL 0x7Fu

/* ---- SDO (expedited and segmented transfers; block transfer is not used) */

/* Byte 0 of an SDO frame: the command specifier in bits 7-5. */
#define LS_CO_SDO_CS_MASK 0xE0u
/* client -> server (ccs) */
#define LS_CO_SDO_CCS_DOWNLOAD_SEGMENT 0x00u  /* | t << 4 | n << 1 | c */
#define LS_CO_SDO_CCS_DOWNLOAD_INITIATE 0x20u /* | n << 2 | e << 1 | s */
#define LS_CO_SDO_CCS_UPLOAD_INITIATE 0x40u
#define LS_CO_SDO_CCS_UPLOAD_SEGMENT 0x60u /* | t << 4 */
#define LS_CO_SDO_CS_ABORT 0x80u           /* both directions */
#define LS_CO_SDO_CCS_BLOCK_DOWNLOAD 0xC0u /* block transfers (not used: a server may refuse them) */
#define LS_CO_SDO_CCS_BLOCK_UPLOAD 0xA0u
/* server -> client (scs) */
#define LS_CO_SDO_SCS_UPLOAD_SEGMENT 0x00u    /* | t << 4 | n << 1 | c */
#define LS_CO_SDO_SCS_DOWNLOAD_SEGMENT 0x20u  /* | t << 4 */
#define LS_CO_SDO_SCS_UPLOAD_INITIATE 0x40u   /* | n << 2 | e << 1 | s */
#define LS_CO_SDO_SCS_DOWNLOAD_INITIATE 0x60u /* no flags */
/* Flag bits of byte 0. */
#define LS_CO_SDO_SIZE 0x01u      /* s: size indicated */
#define LS_CO_SDO_EXPEDITED 0x02u /* e: expedited (initiate) */
#define LS_CO_SDO_LAST 0x01u      /* c: last segment (segment frames) */
#define LS_CO_SDO_TOGGLE 0x10u    /* t: toggle bit (segment frames) */
#define LS_CO_SDO_EXP_N_SHIFT 2u  /* n: bytes NOT used in an expedited initiate (bits 3-2) */
#define LS_CO_SDO_SEG_N_SHIFT 1u  /* n: bytes NOT used in a segment (bits 3-1) */
#define LS_CO_SDO_SEG_DATA 7u     /* data bytes of a segment */
#define LS_CO_SDO_EXP_DATA 4u     /* data bytes of an expedited transfer */

/* SDO abort codes (CiA 301 table 22). ls_co_abort_name() names each one. */
#define LS_CO_ABORT_TOGGLE 0x05030000u          /* toggle bit not alternated */
#define LS_CO_ABORT_TIMEOUT 0x05040000u         /* SDO protocol timed out */
#define LS_CO_ABORT_CS 0x05040001u              /* command specifier not valid or unknown */
#define LS_CO_ABORT_BLOCK_SIZE 0x05040002u      /* invalid block size */
#define LS_CO_ABORT_SEQ 0x05040003u             /* invalid sequence number */
#define LS_CO_ABORT_CRC 0x05040004u             /* CRC error */
#define LS_CO_ABORT_NO_MEMORY 0x05040005u       /* out of memory */
#define LS_CO_ABORT_ACCESS 0x06010000u          /* unsupported access to an object */
#define LS_CO_ABORT_WRITE_ONLY 0x06010001u      /* attempt to read a write-only object */
#define LS_CO_ABORT_READ_ONLY 0x06010002u       /* attempt to write a read-only object */
#define LS_CO_ABORT_NO_OBJECT 0x06020000u       /* object does not exist in the object dictionary */
#define LS_CO_ABORT_NO_MAP 0x06040041u          /* object cannot be mapped to the PDO */
#define LS_CO_ABORT_MAP_LEN 0x06040042u         /* mapped objects would exceed the PDO length */
#define LS_CO_ABORT_PARAM_INCOMPAT 0x06040043u  /* general parameter incompatibility */
#define LS_CO_ABORT_DEVICE_INCOMPAT 0x06040047u /* general internal incompatibility in the device */
#define LS_CO_ABORT_HARDWARE 0x06060000u        /* access failed due to a hardware error */
#define LS_CO_ABORT_TYPE_LEN 0x06070010u        /* data type does not match, length does not match */
#define LS_CO_ABORT_TYPE_LEN_HIGH 0x06070012u   /* data type does not match, length too high */
#define LS_CO_ABORT_TYPE_LEN_LOW 0x06070013u    /* data type does not match, length too low */
#define LS_CO_ABORT_NO_SUB 0x06090011u          /* sub-index does not exist */
#define LS_CO_ABORT_VALUE 0x06090030u           /* invalid value for parameter */
#define LS_CO_ABORT_VALUE_HIGH 0x06090031u      /* value of parameter written too high */
#define LS_CO_ABORT_VALUE_LOW 0x06090032u       /* value of parameter written too low */
#define LS_CO_ABORT_MAX_LT_MIN 0x06090036u      /* maximum value is less than minimum value */
#define LS_CO_ABORT_NO_RESOURCE 0x060A0023u     /* resource not available: SDO connection */
#define LS_CO_ABORT_GENERAL 0x08000000u         /* general error */
#define LS_CO_ABORT_STORE 0x08000020u           /* data cannot be transferred or stored */
#define LS_CO_ABORT_STORE_LOCAL 0x08000021u     /* ... because of local control */
#define LS_CO_ABORT_STORE_STATE 0x08000022u     /* ... because of the present device state */
#define LS_CO_ABORT_NO_OD 0x08000023u           /* no object dictionary present */
#define LS_CO_ABORT_NO_DATA 0x08000024u         /* no data available */

/* ---- Objects of the communication profile (CiA 301) */

#define LS_CO_OBJ_DEVICE_TYPE 0x1000u     /* u32: bits 0-15 the device profile (402) */
#define LS_CO_OBJ_ERROR_REGISTER 0x1001u  /* u8 */
#define LS_CO_OBJ_DEVICE_NAME 0x1008u     /* VISIBLE_STRING: manufacturer device name */
#define LS_CO_OBJ_COB_ID_SYNC 0x1005u     /* u32 */
#define LS_CO_OBJ_COMM_CYCLE 0x1006u      /* u32, us: the SYNC period */
#define LS_CO_OBJ_COB_ID_EMCY 0x1014u     /* u32 */
#define LS_CO_OBJ_CONSUMER_HB 0x1016u     /* sub n: u32 = node << 16 | time in ms (0: off) */
#define LS_CO_OBJ_PRODUCER_HB 0x1017u     /* u16, ms (0: off) */
#define LS_CO_OBJ_IDENTITY 0x1018u        /* :01 vendor id, :02 product code, :03 revision, :04 serial */
#define LS_CO_OBJ_ERROR_BEHAVIOUR 0x1029u /* :01 communication error: 0 pre-op, 1 no change, 2 stopped */
#define LS_CO_OBJ_RPDO_COMM 0x1400u       /* + n - 1: :01 COB-ID, :02 transmission type */
#define LS_CO_OBJ_RPDO_MAP 0x1600u        /* + n - 1: :00 count, :01.. entries */
#define LS_CO_OBJ_TPDO_COMM 0x1800u /* + n - 1: :01 COB-ID, :02 type, :03 inhibit (100 us), :05 event timer (ms) */
#define LS_CO_OBJ_TPDO_MAP 0x1A00u  /* + n - 1 */

/* The communication profile area: what NMT reset communication restores. */
#define LS_CO_OBJ_COMM_FIRST 0x1000u
#define LS_CO_OBJ_COMM_LAST 0x1FFFu

#define LS_CO_DEVICE_PROFILE_MASK 0xFFFFu
#define LS_CO_PROFILE_DRIVE 402u /* CiA 402 in 0x1000 bits 0-15 */

/* PDO communication parameter sub-indices. */
#define LS_CO_PDO_SUB_COB_ID 1u
#define LS_CO_PDO_SUB_TYPE 2u
#define LS_CO_PDO_SUB_INHIBIT 3u
#define LS_CO_PDO_SUB_EVENT_TIMER 5u
/* Transmission types: 1..240 synchronous (every n-th SYNC), 254/255 event-driven. */
#define LS_CO_PDO_TYPE_SYNC_MIN 1u
#define LS_CO_PDO_TYPE_SYNC_MAX 240u
#define LS_CO_PDO_TYPE_EVENT_MFR 254u
#define LS_CO_PDO_TYPE_EVENT 255u
/* A mapping entry: index << 16 | sub-index << 8 | length in bits. */
#define LS_CO_PDO_MAP_ENTRY(index, sub, bits) (((uint32_t)(index) << 16) | ((uint32_t)(sub) << 8) | (uint32_t)(bits))
#define LS_CO_PDO_MAX_ENTRIES 8u
#define LS_CO_PDO_MAX_PDOS 512u /* per direction: 0x1400-0x15FF, 0x1800-0x19FF */

/* ---- EMCY (CiA 301 7.2.7.1): error code u16, error register u8, 5 vendor bytes */

#define LS_CO_EMCY_LEN 8u
/* A few codes the master acts on by number; ls_co_emcy_name() names them all. */
#define LS_CO_EMCY_NO_ERROR 0x0000u
#define LS_CO_EMCY_COMMUNICATION 0x8100u /* communication, generic */
#define LS_CO_EMCY_HEARTBEAT 0x8130u     /* life guard or heartbeat error */
#define LS_CO_EMCY_BUS_OFF_RECOVERED 0x8140u
#define LS_CO_EMCY_FOLLOWING_ERROR 0x8611u /* CiA 402 */
#define LS_CO_EMCY_PDO_LENGTH 0x8210u      /* PDO not processed due to length error */

/* Error register (0x1001, EMCY byte 2) bits. */
#define LS_CO_ERR_REG_GENERIC 0x01u
#define LS_CO_ERR_REG_CURRENT 0x02u
#define LS_CO_ERR_REG_VOLTAGE 0x04u
#define LS_CO_ERR_REG_TEMPERATURE 0x08u
#define LS_CO_ERR_REG_COMMUNICATION 0x10u
#define LS_CO_ERR_REG_PROFILE 0x20u /* device profile specific */
#define LS_CO_ERR_REG_MANUFACTURER 0x80u

/* ---- Objects of the drive profile (CiA 402) */

#define LS_CO_OBJ_ABORT_CONNECTION 0x6007u  /* i16: what the drive does on a lost heartbeat / NMT stop */
#define LS_CO_OBJ_ERROR_CODE 0x603Fu        /* u16: the last error (an EMCY code) */
#define LS_CO_OBJ_CONTROLWORD 0x6040u       /* u16 */
#define LS_CO_OBJ_STATUSWORD 0x6041u        /* u16 */
#define LS_CO_OBJ_QUICK_STOP_OPTION 0x605Au /* i16 */
#define LS_CO_OBJ_MODES 0x6060u             /* i8: modes of operation */
#define LS_CO_OBJ_MODES_DISPLAY 0x6061u     /* i8 */
#define LS_CO_OBJ_POSITION_ACTUAL 0x6064u   /* i32, position units */
#define LS_CO_OBJ_FOLLOWING_WINDOW 0x6065u  /* u32 */
#define LS_CO_OBJ_FOLLOWING_TIMEOUT 0x6066u /* u16, ms */
#define LS_CO_OBJ_VELOCITY_ACTUAL 0x606Cu   /* i32 */
#define LS_CO_OBJ_TORQUE_ACTUAL 0x6077u     /* i16, per mille of rated torque */
#define LS_CO_OBJ_TARGET_POSITION 0x607Au   /* i32 */
#define LS_CO_OBJ_HOME_OFFSET 0x607Cu       /* i32 */
#define LS_CO_OBJ_SW_POSITION_LIMIT 0x607Du /* :01 min, :02 max, i32 */
#define LS_CO_OBJ_QUICK_STOP_DECEL 0x6085u  /* u32, position units / s^2 */
#define LS_CO_OBJ_HOMING_METHOD 0x6098u     /* i8 */
#define LS_CO_OBJ_VELOCITY_OFFSET 0x60B1u   /* i32: velocity feed-forward in CSP */
#define LS_CO_OBJ_TORQUE_OFFSET 0x60B2u     /* i16 */
#define LS_CO_OBJ_INTERP_PERIOD 0x60C2u     /* :01 u8 value, :02 i8 index: value x 10^index s */
#define LS_CO_OBJ_FOLLOWING_ACTUAL 0x60F4u  /* i32: following error actual value */
#define LS_CO_OBJ_SUPPORTED_MODES 0x6502u   /* u32: bit (mode - 1) set when the mode is supported */

/* Modes of operation (0x6060/0x6061). */
#define LS_CO_MODE_PP 1   /* profile position */
#define LS_CO_MODE_PV 3   /* profile velocity */
#define LS_CO_MODE_HM 6   /* homing */
#define LS_CO_MODE_CSP 8  /* cyclic synchronous position */
#define LS_CO_MODE_CSV 9  /* cyclic synchronous velocity */
#define LS_CO_MODE_CST 10 /* cyclic synchronous torque */

/* Abort connection option code (0x6007): the drive's reaction to a lost
 * heartbeat, bus-off or NMT stop while its power stage is on. */
#define LS_CO_ABORT_CONN_NONE 0
#define LS_CO_ABORT_CONN_FAULT 1
#define LS_CO_ABORT_CONN_DISABLE_VOLTAGE 2
#define LS_CO_ABORT_CONN_QUICK_STOP 3

/* Quick stop option code (0x605A): 0 disables the drive at once; 1-4 stop
 * (on a ramp) and go to SWITCH ON DISABLED; 5-8 stop and stay in QUICK
 * STOP ACTIVE (from where enable operation resumes). */
#define LS_CO_QS_DISABLE_DRIVE 0
#define LS_CO_QS_STAY_MIN 5
#define LS_CO_QS_STAY_MAX 8

/* Homing methods (0x6098) on the current position: it becomes the home
 * offset 0x607C (37 in CiA 402 v4; 35 in earlier editions). */
#define LS_CO_HOMING_CURRENT_POSITION 37
#define LS_CO_HOMING_CURRENT_POSITION_OLD 35

/* Statusword bits (0x6041). */
#define LS_CO_SW_READY_TO_SWITCH_ON 0x0001u
#define LS_CO_SW_SWITCHED_ON 0x0002u
#define LS_CO_SW_OPERATION_ENABLED 0x0004u
#define LS_CO_SW_FAULT 0x0008u
#define LS_CO_SW_VOLTAGE_ENABLED 0x0010u
#define LS_CO_SW_QUICK_STOP 0x0020u /* 0 = quick stop active */
#define LS_CO_SW_SWITCH_ON_DISABLED 0x0040u
#define LS_CO_SW_WARNING 0x0080u
#define LS_CO_SW_REMOTE 0x0200u
#define LS_CO_SW_TARGET_REACHED 0x0400u
#define LS_CO_SW_INTERNAL_LIMIT 0x0800u
#define LS_CO_SW_OMS12 0x1000u /* CSP: drive follows the target; HM: homing attained */
#define LS_CO_SW_OMS13 0x2000u /* CSP: following error; HM: homing error */

/* The power state machine's states from the statusword: (sw & mask) == value. */
#define LS_CO_SW_STATE_MASK_SHORT 0x004Fu         /* bits 0-3 and 6 */
#define LS_CO_SW_STATE_MASK_LONG 0x006Fu          /* bits 0-3, 5 and 6 */
#define LS_CO_SW_NOT_READY 0x0000u                /* short mask */
#define LS_CO_SW_SWITCH_ON_DISABLED_STATE 0x0040u /* short mask */
#define LS_CO_SW_READY_STATE 0x0021u              /* long mask */
#define LS_CO_SW_SWITCHED_ON_STATE 0x0023u        /* long mask */
#define LS_CO_SW_ENABLED_STATE 0x0027u            /* long mask */
#define LS_CO_SW_QUICK_STOP_STATE 0x0007u         /* long mask */
#define LS_CO_SW_FAULT_REACTION_STATE 0x000Fu     /* short mask */
#define LS_CO_SW_FAULT_STATE 0x0008u              /* short mask */

/* Controlword (0x6040): bits and the device control commands (CiA 402 table 36). */
#define LS_CO_CW_SWITCH_ON 0x0001u
#define LS_CO_CW_ENABLE_VOLTAGE 0x0002u
#define LS_CO_CW_QUICK_STOP 0x0004u /* 0 = quick stop */
#define LS_CO_CW_ENABLE_OPERATION 0x0008u
#define LS_CO_CW_FAULT_RESET 0x0080u /* acts on its rising edge */
#define LS_CO_CW_HALT 0x0100u
#define LS_CO_CW_HOMING_START 0x0010u         /* HM: operation mode specific bit 4, acts on its rising edge */
#define LS_CO_CW_CMD_SHUTDOWN 0x0006u         /* -> READY TO SWITCH ON */
#define LS_CO_CW_CMD_SWITCH_ON 0x0007u        /* -> SWITCHED ON (also: disable operation) */
#define LS_CO_CW_CMD_ENABLE_OPERATION 0x000Fu /* -> OPERATION ENABLED */
#define LS_CO_CW_CMD_DISABLE_VOLTAGE 0x0000u  /* -> SWITCH ON DISABLED */
#define LS_CO_CW_CMD_QUICK_STOP 0x0002u       /* -> QUICK STOP ACTIVE */

/* ---- EDS/DCF data types (CiA 306) of the objects the master reads or writes */

#define LS_CO_TYPE_BOOLEAN 0x0001u
#define LS_CO_TYPE_INTEGER8 0x0002u
#define LS_CO_TYPE_INTEGER16 0x0003u
#define LS_CO_TYPE_INTEGER32 0x0004u
#define LS_CO_TYPE_UNSIGNED8 0x0005u
#define LS_CO_TYPE_UNSIGNED16 0x0006u
#define LS_CO_TYPE_UNSIGNED32 0x0007u
#define LS_CO_TYPE_REAL32 0x0008u
#define LS_CO_TYPE_VISIBLE_STRING 0x0009u
#define LS_CO_TYPE_OCTET_STRING 0x000Au
#define LS_CO_TYPE_UNICODE_STRING 0x000Bu
#define LS_CO_TYPE_TIME_OF_DAY 0x000Cu     /* 48 bits: ms after midnight (28) + days since 1984 (16) */
#define LS_CO_TYPE_TIME_DIFFERENCE 0x000Du /* 48 bits, as TIME_OF_DAY */
#define LS_CO_TYPE_DOMAIN 0x000Fu
#define LS_CO_TYPE_INTEGER24 0x0010u
#define LS_CO_TYPE_REAL64 0x0011u
#define LS_CO_TYPE_INTEGER40 0x0012u
#define LS_CO_TYPE_INTEGER48 0x0013u
#define LS_CO_TYPE_INTEGER56 0x0014u
#define LS_CO_TYPE_INTEGER64 0x0015u
#define LS_CO_TYPE_UNSIGNED24 0x0016u
#define LS_CO_TYPE_UNSIGNED40 0x0018u
#define LS_CO_TYPE_UNSIGNED48 0x0019u
#define LS_CO_TYPE_UNSIGNED56 0x001Au
#define LS_CO_TYPE_UNSIGNED64 0x001Bu
/* 0x000E and 0x0017 are reserved; above 0x001B come the complex and
 * manufacturer-specific types, which EDS files describe in sections of
 * their own. */

/* The size in bytes of a fixed-size data type above; 0 for strings, DOMAIN
 * and types not listed. */
unsigned ls_co_type_size(uint16_t data_type);

/* "UNSIGNED32" etc. for a data type above (CiA 301's names); NULL for a
 * reserved or unknown code, so that a caller can tell a basic type from
 * anything else. O(1); any context. */
const char *ls_co_type_name(uint16_t data_type);

/* ---- Object codes of an EDS/DCF's ObjectType (CiA 301 table 42, CiA 306) */

#define LS_CO_OBJECT_NULL 0x0u
#define LS_CO_OBJECT_DOMAIN 0x2u
#define LS_CO_OBJECT_DEFTYPE 0x5u
#define LS_CO_OBJECT_DEFSTRUCT 0x6u
#define LS_CO_OBJECT_VAR 0x7u
#define LS_CO_OBJECT_ARRAY 0x8u
#define LS_CO_OBJECT_RECORD 0x9u

/* ---- Names, for one-line messages. Never NULL; O(n) in a small table;
 * any context (constant data only). */

/* "toggle bit not alternated" for LS_CO_ABORT_TOGGLE; "unknown abort code"
 * for a code not in CiA 301's table. */
const char *ls_co_abort_name(uint32_t abort_code);

/* "following error" for 0x8611, "heartbeat error" for 0x8130: the most
 * specific CiA 301 / CiA 402 name of an EMCY error code (an exact entry,
 * else its class: 0x23xx "current, device output side", 0xFFxx "device
 * specific", ...); "no error" for 0x0000. */
const char *ls_co_emcy_name(uint16_t error_code);

/* The error register bits (0x1001) CiA 301 associates with an EMCY code:
 * generic for every error, plus its class's bit (current, voltage,
 * temperature, communication for 0x81xx-0x82xx, device profile for the
 * other monitoring codes 0x83xx-0x8Fxx, manufacturer for 0xFFxx); 0 for
 * 0x0000. O(1); any context. */
uint8_t ls_co_error_register_bits(uint16_t error_code);

/* "OPERATIONAL" etc. for a heartbeat state byte; "unknown" otherwise. */
const char *ls_co_nmt_state_name(uint8_t state);

#ifdef __cplusplus
}
#endif

#endif /* LS_CANOPEN_H */
