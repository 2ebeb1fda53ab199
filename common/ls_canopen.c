/* Names of CANopen codes (ls_canopen.h): SDO abort codes (CiA 301), EMCY
 * error codes (CiA 301 and the drive profile's, CiA 402) and NMT states.
 * Constant tables, searched linearly: they serve log lines and answers,
 * not the control loop's hot path. */
#include "ls_canopen.h"

#include <stddef.h>

typedef struct {
    uint32_t code;
    const char *name;
} code_name_t;

static const code_name_t k_aborts[] = {
    { LS_CO_ABORT_TOGGLE, "toggle bit not alternated" },
    { LS_CO_ABORT_TIMEOUT, "SDO protocol timed out" },
    { LS_CO_ABORT_CS, "command specifier not valid or unknown" },
    { LS_CO_ABORT_BLOCK_SIZE, "invalid block size" },
    { LS_CO_ABORT_SEQ, "invalid sequence number" },
    { LS_CO_ABORT_CRC, "CRC error" },
    { LS_CO_ABORT_NO_MEMORY, "out of memory" },
    { LS_CO_ABORT_ACCESS, "unsupported access to an object" },
    { LS_CO_ABORT_WRITE_ONLY, "attempt to read a write-only object" },
    { LS_CO_ABORT_READ_ONLY, "attempt to write a read-only object" },
    { LS_CO_ABORT_NO_OBJECT, "object does not exist in the object dictionary" },
    { LS_CO_ABORT_NO_MAP, "object cannot be mapped to the PDO" },
    { LS_CO_ABORT_MAP_LEN, "the mapped objects would exceed the PDO length" },
    { LS_CO_ABORT_PARAM_INCOMPAT, "general parameter incompatibility" },
    { LS_CO_ABORT_DEVICE_INCOMPAT, "general internal incompatibility in the device" },
    { LS_CO_ABORT_HARDWARE, "access failed due to a hardware error" },
    { LS_CO_ABORT_TYPE_LEN, "data type does not match: length of service parameter does not match" },
    { LS_CO_ABORT_TYPE_LEN_HIGH, "data type does not match: length of service parameter too high" },
    { LS_CO_ABORT_TYPE_LEN_LOW, "data type does not match: length of service parameter too low" },
    { LS_CO_ABORT_NO_SUB, "sub-index does not exist" },
    { LS_CO_ABORT_VALUE, "invalid value for parameter" },
    { LS_CO_ABORT_VALUE_HIGH, "value of parameter written too high" },
    { LS_CO_ABORT_VALUE_LOW, "value of parameter written too low" },
    { LS_CO_ABORT_MAX_LT_MIN, "maximum value is less than minimum value" },
    { LS_CO_ABORT_NO_RESOURCE, "resource not available: SDO connection" },
    { LS_CO_ABORT_GENERAL, "general error" },
    { LS_CO_ABORT_STORE, "data cannot be transferred or stored to the application" },
    { LS_CO_ABORT_STORE_LOCAL, "data cannot be transferred or stored because of local control" },
    { LS_CO_ABORT_STORE_STATE, "data cannot be transferred or stored in the present device state" },
    { LS_CO_ABORT_NO_OD, "no object dictionary is present" },
    { LS_CO_ABORT_NO_DATA, "no data available" },
};

/* Exact EMCY codes: CiA 301 (communication) and CiA 402 (drives). */
static const code_name_t k_emcy[] = {
    { 0x0000u, "no error" },
    { 0x1000u, "generic error" },
    { 0x2110u, "short circuit or earth leakage, input side" },
    { 0x2120u, "earth leakage, input side" },
    { 0x2310u, "continuous over-current" },
    { 0x2311u, "continuous over-current no. 1" },
    { 0x2312u, "continuous over-current no. 2" },
    { 0x2320u, "short circuit or earth leakage, motor side" },
    { 0x2330u, "earth leakage, motor side" },
    { 0x3110u, "mains over-voltage" },
    { 0x3120u, "mains under-voltage" },
    { 0x3130u, "mains phase failure" },
    { 0x3210u, "DC link over-voltage" },
    { 0x3220u, "DC link under-voltage" },
    { 0x3230u, "load error" },
    { 0x3310u, "output over-voltage" },
    { 0x4110u, "excess ambient temperature" },
    { 0x4120u, "ambient temperature too low" },
    { 0x4210u, "excess device temperature" },
    { 0x4220u, "device temperature too low" },
    { 0x4310u, "excess drive temperature" },
    { 0x4320u, "drive temperature too low" },
    { 0x4410u, "excess supply temperature" },
    { 0x5110u, "supply low voltage" },
    { 0x5210u, "measurement circuit" },
    { 0x5400u, "power section" },
    { 0x5410u, "output stages" },
    { 0x5530u, "data storage (non-volatile memory)" },
    { 0x6010u, "software reset (watchdog)" },
    { 0x6320u, "parameter error" },
    { 0x7110u, "brake chopper" },
    { 0x7120u, "motor" },
    { 0x7121u, "motor blocked" },
    { 0x7122u, "motor error or commutation malfunction" },
    { 0x7300u, "sensor" },
    { 0x7305u, "incremental sensor 1 fault" },
    { 0x7310u, "speed sensor" },
    { 0x7320u, "position sensor" },
    { 0x8110u, "CAN overrun (objects lost)" },
    { 0x8120u, "CAN in error passive mode" },
    { LS_CO_EMCY_HEARTBEAT, "heartbeat error" },
    { LS_CO_EMCY_BUS_OFF_RECOVERED, "recovered from bus-off" },
    { 0x8150u, "CAN-ID collision" },
    { LS_CO_EMCY_PDO_LENGTH, "PDO not processed due to length error" },
    { 0x8220u, "PDO length exceeded" },
    { 0x8240u, "unexpected SYNC data length" },
    { 0x8250u, "RPDO time-out" },
    { 0x8311u, "excess torque" },
    { 0x8312u, "difficult start-up" },
    { 0x8313u, "standstill torque" },
    { 0x8400u, "velocity controller" },
    { 0x8500u, "position controller" },
    { LS_CO_EMCY_FOLLOWING_ERROR, "following error" },
    { 0x8612u, "reference limit" },
    { 0x8700u, "sync controller" },
    { 0x9000u, "external error" },
    { 0xF001u, "deceleration" },
    { 0xF002u, "sub-synchronous run" },
    { 0xF003u, "stroke operation" },
    { 0xF004u, "control" },
};

/* EMCY classes: the code's high byte, then its high nibble (CiA 301 table 21). */
static const code_name_t k_emcy_class[] = {
    { 0x10u, "generic error" },
    { 0x20u, "current" },
    { 0x21u, "current, device input side" },
    { 0x22u, "current inside the device" },
    { 0x23u, "current, device output side" },
    { 0x30u, "voltage" },
    { 0x31u, "mains voltage" },
    { 0x32u, "voltage inside the device" },
    { 0x33u, "output voltage" },
    { 0x40u, "temperature" },
    { 0x41u, "ambient temperature" },
    { 0x42u, "device temperature" },
    { 0x43u, "drive temperature" },
    { 0x50u, "device hardware" },
    { 0x60u, "device software" },
    { 0x61u, "internal software" },
    { 0x62u, "user software" },
    { 0x63u, "data set" },
    { 0x70u, "additional modules" },
    { 0x71u, "power" },
    { 0x73u, "sensor" },
    { 0x75u, "communication" },
    { 0x80u, "monitoring" },
    { 0x81u, "communication" },
    { 0x82u, "protocol error" },
    { 0x83u, "torque control" },
    { 0x84u, "velocity control" },
    { 0x85u, "position control" },
    { 0x86u, "positioning control" },
    { 0x87u, "sync control" },
    { 0x88u, "winding control" },
    { 0x90u, "external error" },
    { 0xF0u, "additional functions" },
    { 0xFFu, "device specific" },
};

static const char *lookup(const code_name_t *t, size_t n, uint32_t code)
{
    for (size_t i = 0; i < n; i++) {
        if (t[i].code == code) {
            return t[i].name;
        }
    }
    return NULL;
}

#define N_OF(a) (sizeof(a) / sizeof((a)[0]))

const char *ls_co_abort_name(uint32_t abort_code)
{
    const char *s = lookup(k_aborts, N_OF(k_aborts), abort_code);
    return s != NULL ? s : "unknown abort code";
}

const char *ls_co_emcy_name(uint16_t error_code)
{
    const char *s = lookup(k_emcy, N_OF(k_emcy), error_code);
    if (s == NULL) {
        s = lookup(k_emcy_class, N_OF(k_emcy_class), (uint32_t)error_code >> 8);
    }
    if (s == NULL) {
        s = lookup(k_emcy_class, N_OF(k_emcy_class), ((uint32_t)error_code >> 8) & 0xF0u);
    }
    return s != NULL ? s : "unknown error code";
}

uint8_t ls_co_error_register_bits(uint16_t error_code)
{
    if (error_code == LS_CO_EMCY_NO_ERROR) {
        return 0u;
    }
    uint8_t bits = LS_CO_ERR_REG_GENERIC;
    switch (error_code >> 12) { /* the class's high nibble, CiA 301 table 21 */
    case 0x2: bits |= LS_CO_ERR_REG_CURRENT; break;
    case 0x3: bits |= LS_CO_ERR_REG_VOLTAGE; break;
    case 0x4: bits |= LS_CO_ERR_REG_TEMPERATURE; break;
    case 0x8: bits |= (error_code >> 8) <= 0x82u ? LS_CO_ERR_REG_COMMUNICATION : LS_CO_ERR_REG_PROFILE; break;
    case 0xF:
        if ((error_code >> 8) == 0xFFu) {
            bits |= LS_CO_ERR_REG_MANUFACTURER;
        }
        break;
    default: break;
    }
    return bits;
}

const char *ls_co_nmt_state_name(uint8_t state)
{
    switch (state) {
    case LS_CO_NMT_BOOTUP: return "BOOT-UP";
    case LS_CO_NMT_STOPPED: return "STOPPED";
    case LS_CO_NMT_OPERATIONAL: return "OPERATIONAL";
    case LS_CO_NMT_PREOPERATIONAL: return "PRE-OPERATIONAL";
    default: return "unknown";
    }
}

unsigned ls_co_type_size(uint16_t data_type)
{
    switch (data_type) {
    case LS_CO_TYPE_BOOLEAN:
    case LS_CO_TYPE_INTEGER8:
    case LS_CO_TYPE_UNSIGNED8: return 1u;
    case LS_CO_TYPE_INTEGER16:
    case LS_CO_TYPE_UNSIGNED16: return 2u;
    case LS_CO_TYPE_INTEGER24:
    case LS_CO_TYPE_UNSIGNED24: return 3u;
    case LS_CO_TYPE_INTEGER32:
    case LS_CO_TYPE_UNSIGNED32:
    case LS_CO_TYPE_REAL32: return 4u;
    case LS_CO_TYPE_INTEGER40:
    case LS_CO_TYPE_UNSIGNED40: return 5u;
    case LS_CO_TYPE_INTEGER48:
    case LS_CO_TYPE_UNSIGNED48:
    case LS_CO_TYPE_TIME_OF_DAY:
    case LS_CO_TYPE_TIME_DIFFERENCE: return 6u;
    case LS_CO_TYPE_INTEGER56:
    case LS_CO_TYPE_UNSIGNED56: return 7u;
    case LS_CO_TYPE_INTEGER64:
    case LS_CO_TYPE_UNSIGNED64:
    case LS_CO_TYPE_REAL64: return 8u;
    default: return 0u;
    }
}

const char *ls_co_type_name(uint16_t data_type)
{
    switch (data_type) {
    case LS_CO_TYPE_BOOLEAN: return "BOOLEAN";
    case LS_CO_TYPE_INTEGER8: return "INTEGER8";
    case LS_CO_TYPE_INTEGER16: return "INTEGER16";
    case LS_CO_TYPE_INTEGER32: return "INTEGER32";
    case LS_CO_TYPE_UNSIGNED8: return "UNSIGNED8";
    case LS_CO_TYPE_UNSIGNED16: return "UNSIGNED16";
    case LS_CO_TYPE_UNSIGNED32: return "UNSIGNED32";
    case LS_CO_TYPE_REAL32: return "REAL32";
    case LS_CO_TYPE_VISIBLE_STRING: return "VISIBLE_STRING";
    case LS_CO_TYPE_OCTET_STRING: return "OCTET_STRING";
    case LS_CO_TYPE_UNICODE_STRING: return "UNICODE_STRING";
    case LS_CO_TYPE_TIME_OF_DAY: return "TIME_OF_DAY";
    case LS_CO_TYPE_TIME_DIFFERENCE: return "TIME_DIFFERENCE";
    case LS_CO_TYPE_DOMAIN: return "DOMAIN";
    case LS_CO_TYPE_INTEGER24: return "INTEGER24";
    case LS_CO_TYPE_REAL64: return "REAL64";
    case LS_CO_TYPE_INTEGER40: return "INTEGER40";
    case LS_CO_TYPE_INTEGER48: return "INTEGER48";
    case LS_CO_TYPE_INTEGER56: return "INTEGER56";
    case LS_CO_TYPE_INTEGER64: return "INTEGER64";
    case LS_CO_TYPE_UNSIGNED24: return "UNSIGNED24";
    case LS_CO_TYPE_UNSIGNED40: return "UNSIGNED40";
    case LS_CO_TYPE_UNSIGNED48: return "UNSIGNED48";
    case LS_CO_TYPE_UNSIGNED56: return "UNSIGNED56";
    case LS_CO_TYPE_UNSIGNED64: return "UNSIGNED64";
    default: return NULL;
    }
}
