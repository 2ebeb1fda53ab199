/* ls_eds: the two vendor files of LS_VENDOR_EDS_DIR (a maxon EPOS4 DCF and
 * ros2_canopen's CiA 402 test drive EDS; read in place, never copied here)
 * with every quirk their README lists, then hand-written files for the
 * syntax, the values and each refusal's one line. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "alloc_counter.h"
#include "ls_canopen.h"
#include "ls_eds.h"

#define EPOS4_DCF "epos4_50_15_can_ec90flat_gp52c_mile800_node1.dcf"
#define ROS2_EDS "ros2_canopen_cia402_slave.eds"

static ls_eds_t g_eds;
static char g_msg[LS_EDS_MSG_MAX];

/* ---- helpers ----------------------------------------------------------- */

static void load_shared(const char *file)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", LS_VENDOR_EDS_DIR, file);
    if (access(path, R_OK) != 0) {
        fail_msg("%s is missing: the vendor EDS/DCF files live in LS_VENDOR_EDS_DIR (now %s); configure with "
                 "-DLS_VENDOR_EDS_DIR=DIR where DIR holds them",
                 path, LS_VENDOR_EDS_DIR);
    }
    if (ls_eds_load(&g_eds, path, g_msg, sizeof g_msg) != LS_OK) {
        fail_msg("%s", g_msg);
    }
    assert_string_equal(g_msg, "");
}

static int load_text(const char *text)
{
    return ls_eds_load_buffer(&g_eds, "t.eds", text, strlen(text), g_msg, sizeof g_msg);
}

static void assert_refused(const char *text, const char *line)
{
    assert_int_equal(load_text(text), LS_EINVAL);
    assert_string_equal(g_msg, line);
    assert_int_equal(ls_eds_count(&g_eds), 0); /* never half loaded */
}

static const ls_eds_entry_t *must_find(uint16_t index, uint8_t sub)
{
    const ls_eds_entry_t *e = ls_eds_find(&g_eds, index, sub);
    if (e == NULL) {
        fail_msg("0x%04X:%02X is missing", (unsigned)index, (unsigned)sub);
    }
    return e;
}

static ls_eds_value_t field_of(uint16_t index, uint8_t sub, ls_eds_field_id_t f, uint8_t node)
{
    ls_eds_value_t v;
    assert_int_equal(ls_eds_field(&g_eds, must_find(index, sub), f, node, &v), LS_OK);
    return v;
}

static ls_eds_value_t value_of(uint16_t index, uint8_t sub, uint8_t node)
{
    ls_eds_value_t v;
    assert_int_equal(ls_eds_value(&g_eds, must_find(index, sub), node, &v), LS_OK);
    return v;
}

static uint64_t uint_of(uint16_t index, uint8_t sub, uint8_t node)
{
    ls_eds_value_t v = value_of(index, sub, node);
    if (v.kind != LS_EDS_VALUE_UINT) {
        fail_msg("0x%04X:%02X has no unsigned value (kind %d)", (unsigned)index, (unsigned)sub, (int)v.kind);
    }
    return v.u;
}

static int64_t int_of(uint16_t index, uint8_t sub, uint8_t node)
{
    ls_eds_value_t v = value_of(index, sub, node);
    if (v.kind != LS_EDS_VALUE_INT) {
        fail_msg("0x%04X:%02X has no signed value (kind %d)", (unsigned)index, (unsigned)sub, (int)v.kind);
    }
    return v.i;
}

/* A PDO's mapping as the README lists it: each entry's object exists in
 * the same file, is mappable, and its length is the object's size. */
static void assert_mapping(uint16_t map_index, uint8_t node, const uint32_t *objects, unsigned n)
{
    assert_int_equal(uint_of(map_index, 0, node), n);
    for (unsigned k = 0; k < n; k++) {
        const uint64_t entry = uint_of(map_index, (uint8_t)(k + 1u), node);
        const uint16_t index = (uint16_t)(entry >> 16);
        const uint8_t sub = (uint8_t)(entry >> 8);
        if (((uint32_t)index << 8 | sub) != objects[k]) {
            fail_msg("0x%04X:%02X maps 0x%08llX, expected object 0x%06X", (unsigned)map_index, k + 1u,
                     (unsigned long long)entry, (unsigned)objects[k]);
        }
        const ls_eds_entry_t *o = must_find(index, sub);
        assert_true(ls_eds_mappable(o));
        assert_int_equal(entry & 0xFFu, 8u * ls_eds_size(o));
    }
}

#define OBJ(index, sub) (((uint32_t)(index) << 8) | (sub))

/* A PDO's power-on mapping: the mapping object and the objects it maps. */
typedef struct {
    uint16_t map_index;
    unsigned n;
    uint32_t objects[LS_CO_PDO_MAX_ENTRIES];
} pdo_map_t;

static void assert_mappings(const pdo_map_t *maps, size_t n, uint8_t node)
{
    for (size_t i = 0; i < n; i++) {
        assert_mapping(maps[i].map_index, node, maps[i].objects, maps[i].n);
    }
}

/* ---- the EPOS4 DCF ------------------------------------------------------ */

static void test_the_epos4_dcf_loads_with_its_identity(void **state)
{
    (void)state;
    load_shared(EPOS4_DCF);
    assert_int_equal(ls_eds_count(&g_eds), 652);
    ls_eds_device_t d;
    assert_int_equal(ls_eds_device(&g_eds, &d), LS_OK);
    assert_string_equal(d.vendor_name, "maxon motor ag");
    assert_string_equal(d.product_name, "EPOS4 Module 50/15");
    assert_true(d.has_vendor_number && d.has_product_number && d.has_revision_number);
    assert_int_equal(d.vendor_number, 0x000000FB);
    assert_int_equal(d.product_number, 0x65520000);
    assert_int_equal(d.revision_number, 0x01700000);
    assert_int_equal(d.dcf_node_id, 1); /* commissioned as node 1 */
}

/* DefaultValue=$NODEID+0x40000180 but ParameterValue=0x00000181: the DCF's
 * value wins and stays node 1's whatever the node asked. */
static void test_the_epos4_dcf_keeps_node_1s_absolute_cob_ids(void **state)
{
    (void)state;
    load_shared(EPOS4_DCF);
    assert_int_equal(uint_of(0x1800, 1, 5), 0x181);
    ls_eds_value_t v = field_of(0x1800, 1, LS_EDS_DEFAULT, 5);
    assert_int_equal(v.kind, LS_EDS_VALUE_UINT);
    assert_true(v.node_relative);
    assert_int_equal(v.u, 0x40000185);
    v = field_of(0x1800, 1, LS_EDS_PARAMETER, 5);
    assert_false(v.node_relative);
    assert_int_equal(v.u, 0x181);
}

static void test_every_epos4_pdo_is_valid_and_synchronous_with_its_power_on_mapping(void **state)
{
    (void)state;
    load_shared(EPOS4_DCF);
    const uint8_t node = 9;
    for (unsigned n = 1; n <= 4; n++) {
        const uint64_t rcob = uint_of((uint16_t)(LS_CO_OBJ_RPDO_COMM + n - 1u), LS_CO_PDO_SUB_COB_ID, node);
        const uint64_t tcob = uint_of((uint16_t)(LS_CO_OBJ_TPDO_COMM + n - 1u), LS_CO_PDO_SUB_COB_ID, node);
        assert_int_equal(rcob & LS_CO_COBID_INVALID, 0);
        assert_int_equal(tcob & LS_CO_COBID_INVALID, 0);
        assert_int_equal(rcob & LS_CO_COB_MASK, LS_CO_COB_RPDO(n, 1)); /* node 1's */
        assert_int_equal(tcob & LS_CO_COB_MASK, LS_CO_COB_TPDO(n, 1));
        assert_int_equal(uint_of((uint16_t)(LS_CO_OBJ_RPDO_COMM + n - 1u), LS_CO_PDO_SUB_TYPE, node), 1);
        assert_int_equal(uint_of((uint16_t)(LS_CO_OBJ_TPDO_COMM + n - 1u), LS_CO_PDO_SUB_TYPE, node), 1);
        assert_int_equal(uint_of((uint16_t)(LS_CO_OBJ_TPDO_COMM + n - 1u), LS_CO_PDO_SUB_INHIBIT, node), 10);
    }
    static const pdo_map_t maps[] = {
        { LS_CO_OBJ_RPDO_MAP + 0, 2, { OBJ(0x6040, 0), OBJ(0x60FF, 0) } },
        { LS_CO_OBJ_RPDO_MAP + 1, 2, { OBJ(0x607A, 0), OBJ(0x6081, 0) } },
        { LS_CO_OBJ_RPDO_MAP + 2, 2, { OBJ(0x6083, 0), OBJ(0x6084, 0) } },
        { LS_CO_OBJ_RPDO_MAP + 3, 2, { OBJ(0x6071, 0), OBJ(0x6060, 0) } },
        { LS_CO_OBJ_TPDO_MAP + 0, 2, { OBJ(0x6041, 0), OBJ(0x6061, 0) } },
        { LS_CO_OBJ_TPDO_MAP + 1, 2, { OBJ(0x606B, 0), OBJ(0x606C, 0) } },
        { LS_CO_OBJ_TPDO_MAP + 2, 2, { OBJ(0x6064, 0), OBJ(0x30D3, 1) } },
        { LS_CO_OBJ_TPDO_MAP + 3, 0, { 0 } }, /* TPDO4: nothing mapped */
    };
    assert_mappings(maps, sizeof maps / sizeof maps[0], node);
}

static void test_the_epos4_dcf_has_the_402_objects_and_lacks_what_its_readme_says(void **state)
{
    (void)state;
    load_shared(EPOS4_DCF);
    const uint16_t present[] = { 0x6040, 0x6041, 0x6060, 0x6061, 0x607A, 0x6064, 0x606C, 0x6077,
                                 0x60B1, 0x6098, 0x6065, 0x605A, 0x6007, 0x6502, 0x1005, 0x1017 };
    for (size_t i = 0; i < sizeof present / sizeof present[0]; i++) {
        must_find(present[i], 0);
    }
    assert_non_null(ls_eds_object(&g_eds, 0x1014));
    assert_non_null(ls_eds_object(&g_eds, 0x1029));
    const uint16_t absent[] = { LS_CO_OBJ_COMM_CYCLE, LS_CO_OBJ_HOME_OFFSET, 0x608F, 0x6091, 0x6092 };
    for (size_t i = 0; i < sizeof absent / sizeof absent[0]; i++) {
        assert_null(ls_eds_object(&g_eds, absent[i]));
        assert_null(ls_eds_find(&g_eds, absent[i], 0));
    }
    /* interpolation period 10^-3 s x 0, to be written by the master */
    assert_int_equal(uint_of(LS_CO_OBJ_INTERP_PERIOD, 1, 1), 0);
    assert_int_equal(int_of(LS_CO_OBJ_INTERP_PERIOD, 2, 1), -3);
    assert_int_equal(must_find(LS_CO_OBJ_INTERP_PERIOD, 2)->data_type, LS_CO_TYPE_INTEGER8);
    assert_int_equal(uint_of(LS_CO_OBJ_FOLLOWING_WINDOW, 0, 1), 20000);
    assert_int_equal(int_of(LS_CO_OBJ_QUICK_STOP_OPTION, 0, 1), 6); /* stays in QUICK STOP ACTIVE */
    assert_int_equal(int_of(LS_CO_OBJ_ABORT_CONNECTION, 0, 1), 3);  /* quick stop on a lost heartbeat */
    assert_int_equal(int_of(LS_CO_OBJ_MODES, 0, 1), LS_CO_MODE_PP); /* powers on in profile position */
    /* COB-ID SYNC 0x80, const; two consumer heartbeat entries; no producer heartbeat */
    const ls_eds_entry_t *sync = must_find(LS_CO_OBJ_COB_ID_SYNC, 0);
    assert_int_equal(sync->access, LS_EDS_CONST);
    assert_false(ls_eds_writable(sync));
    assert_int_equal(uint_of(LS_CO_OBJ_COB_ID_SYNC, 0, 1), LS_CO_COB_SYNC);
    assert_int_equal(uint_of(LS_CO_OBJ_CONSUMER_HB, 0, 1), 2);
    must_find(LS_CO_OBJ_CONSUMER_HB, 2);
    assert_null(ls_eds_find(&g_eds, LS_CO_OBJ_CONSUMER_HB, 3));
    assert_int_equal(uint_of(LS_CO_OBJ_PRODUCER_HB, 0, 1), 0);
    /* the controlword is rw (not rww) and still mappable */
    const ls_eds_entry_t *cw = must_find(LS_CO_OBJ_CONTROLWORD, 0);
    assert_int_equal(cw->access, LS_EDS_RW);
    assert_true(ls_eds_mappable(cw));
    assert_true(ls_eds_writable(cw));
    /* 0x1000, 0x1018 and 0x6502 have no DefaultValue; the DCF gives
     * ParameterValues (what the tool read from the commissioned drive) */
    const uint16_t no_default[][2] = { { LS_CO_OBJ_DEVICE_TYPE, 0 },
                                       { LS_CO_OBJ_IDENTITY, 1 },
                                       { LS_CO_OBJ_IDENTITY, 2 },
                                       { LS_CO_OBJ_IDENTITY, 3 },
                                       { LS_CO_OBJ_SUPPORTED_MODES, 0 } };
    for (size_t i = 0; i < sizeof no_default / sizeof no_default[0]; i++) {
        ls_eds_value_t v = field_of(no_default[i][0], (uint8_t)no_default[i][1], LS_EDS_DEFAULT, 1);
        assert_int_equal(v.kind, LS_EDS_VALUE_NONE);
    }
    assert_int_equal(uint_of(LS_CO_OBJ_DEVICE_TYPE, 0, 1) & LS_CO_DEVICE_PROFILE_MASK, LS_CO_PROFILE_DRIVE);
    assert_int_equal(uint_of(LS_CO_OBJ_IDENTITY, 1, 1), 0xFB);
    const uint64_t modes = uint_of(LS_CO_OBJ_SUPPORTED_MODES, 0, 1);
    const int supported[] = { LS_CO_MODE_PP,  LS_CO_MODE_PV,  LS_CO_MODE_HM,
                              LS_CO_MODE_CSP, LS_CO_MODE_CSV, LS_CO_MODE_CST };
    for (size_t i = 0; i < sizeof supported / sizeof supported[0]; i++) {
        assert_true((modes >> (supported[i] - 1)) & 1u);
    }
    /* a VISIBLE_STRING and a 64-bit value */
    ls_eds_value_t v = value_of(0x1008, 0, 1);
    assert_int_equal(v.kind, LS_EDS_VALUE_TEXT);
    assert_string_equal(v.text, "EPOS4");
    assert_int_equal(uint_of(0x2100, 1, 1), 0x0000682129001321ull);
    assert_int_equal(ls_eds_size(must_find(0x2100, 1)), 8);
}

/* ---- ros2_canopen's CiA 402 test drive ---------------------------------- */

static void test_the_ros2_canopen_eds_loads_with_its_identity(void **state)
{
    (void)state;
    load_shared(ROS2_EDS);
    assert_int_equal(ls_eds_count(&g_eds), 180);
    ls_eds_device_t d;
    assert_int_equal(ls_eds_device(&g_eds, &d), LS_OK);
    assert_string_equal(d.vendor_name, "ROS-Industrial");
    assert_string_equal(d.product_name, "CIA402VTD");
    assert_true(d.has_vendor_number);
    assert_int_equal(d.vendor_number, 0x555);
    assert_false(d.has_product_number); /* [DeviceInfo] gives neither */
    assert_false(d.has_revision_number);
    assert_int_equal(d.dcf_node_id, 0); /* an EDS: no commissioning */
    assert_int_equal(uint_of(LS_CO_OBJ_IDENTITY, 1, 1), 0x555);
    assert_int_equal(uint_of(LS_CO_OBJ_DEVICE_TYPE, 0, 1), 0xFFFF0192);
}

static void test_the_ros2_canopen_eds_has_its_quirks(void **state)
{
    (void)state;
    load_shared(ROS2_EDS);
    const uint16_t absent[] = { LS_CO_OBJ_TORQUE_ACTUAL, LS_CO_OBJ_ABORT_CONNECTION, LS_CO_OBJ_COMM_CYCLE, 0x6091,
                                0x6092 };
    for (size_t i = 0; i < sizeof absent / sizeof absent[0]; i++) {
        assert_null(ls_eds_object(&g_eds, absent[i]));
    }
    assert_non_null(ls_eds_object(&g_eds, 0x608F));
    assert_int_equal(ls_eds_object(&g_eds, 0x608F)->object_type, LS_CO_OBJECT_ARRAY);
    /* 0x6502 = 0xA5: PP, PV, HM, CSP; not CSV, not CST */
    const uint64_t modes = uint_of(LS_CO_OBJ_SUPPORTED_MODES, 0, 1);
    assert_int_equal(modes, 0xA5);
    assert_true((modes >> (LS_CO_MODE_CSP - 1)) & 1u);
    assert_false((modes >> (LS_CO_MODE_CSV - 1)) & 1u);
    assert_false((modes >> (LS_CO_MODE_CST - 1)) & 1u);
    /* COB-IDs relative to the node, with bit 30; RPDO4 and TPDO4 invalid */
    const uint8_t node = 3;
    for (unsigned n = 1; n <= 4; n++) {
        const uint64_t rcob = uint_of((uint16_t)(LS_CO_OBJ_RPDO_COMM + n - 1u), LS_CO_PDO_SUB_COB_ID, node);
        const uint64_t tcob = uint_of((uint16_t)(LS_CO_OBJ_TPDO_COMM + n - 1u), LS_CO_PDO_SUB_COB_ID, node);
        assert_int_equal(rcob & LS_CO_COB_MASK, LS_CO_COB_RPDO(n, node));
        assert_int_equal(tcob & LS_CO_COB_MASK, LS_CO_COB_TPDO(n, node));
        assert_true(rcob & LS_CO_COBID_NO_RTR);
        assert_true(tcob & LS_CO_COBID_NO_RTR);
        assert_int_equal((rcob & LS_CO_COBID_INVALID) != 0, n == 4);
        assert_int_equal((tcob & LS_CO_COBID_INVALID) != 0, n == 4);
        assert_true(field_of((uint16_t)(LS_CO_OBJ_RPDO_COMM + n - 1u), 1, LS_EDS_DEFAULT, node).node_relative);
        /* RPDOs asynchronous at power-on; TPDO1-3 synchronous, TPDO4 254 */
        assert_int_equal(uint_of((uint16_t)(LS_CO_OBJ_RPDO_COMM + n - 1u), LS_CO_PDO_SUB_TYPE, node),
                         n == 4 ? LS_CO_PDO_TYPE_EVENT_MFR : LS_CO_PDO_TYPE_EVENT);
        assert_int_equal(uint_of((uint16_t)(LS_CO_OBJ_TPDO_COMM + n - 1u), LS_CO_PDO_SUB_TYPE, node),
                         n == 4 ? LS_CO_PDO_TYPE_EVENT_MFR : 1);
    }
    static const pdo_map_t maps[] = {
        { LS_CO_OBJ_RPDO_MAP + 0, 1, { OBJ(0x6040, 0) } },
        { LS_CO_OBJ_RPDO_MAP + 1, 2, { OBJ(0x6040, 0), OBJ(0x6060, 0) } },
        { LS_CO_OBJ_RPDO_MAP + 2, 2, { OBJ(0x6040, 0), OBJ(0x607A, 0) } },
        { LS_CO_OBJ_RPDO_MAP + 3, 2, { OBJ(0x6040, 0), OBJ(0x60FF, 0) } },
        { LS_CO_OBJ_TPDO_MAP + 0, 1, { OBJ(0x6041, 0) } },
        { LS_CO_OBJ_TPDO_MAP + 1, 2, { OBJ(0x6041, 0), OBJ(0x6061, 0) } },
        { LS_CO_OBJ_TPDO_MAP + 2, 2, { OBJ(0x6041, 0), OBJ(0x6064, 0) } },
        { LS_CO_OBJ_TPDO_MAP + 3, 2, { OBJ(0x6041, 0), OBJ(0x606C, 0) } },
    };
    assert_mappings(maps, sizeof maps / sizeof maps[0], node);
    /* no default for the controlword and the following error window */
    assert_int_equal(value_of(LS_CO_OBJ_CONTROLWORD, 0, 1).kind, LS_EDS_VALUE_NONE);
    assert_int_equal(value_of(LS_CO_OBJ_FOLLOWING_WINDOW, 0, 1).kind, LS_EDS_VALUE_NONE);
    assert_int_equal(must_find(LS_CO_OBJ_CONTROLWORD, 0)->access, LS_EDS_RWW);
    /* interpolation period 1 x 10^-2 s, not mappable */
    assert_int_equal(uint_of(LS_CO_OBJ_INTERP_PERIOD, 1, 1), 1);
    assert_int_equal(int_of(LS_CO_OBJ_INTERP_PERIOD, 2, 1), -2);
    assert_false(ls_eds_mappable(must_find(LS_CO_OBJ_INTERP_PERIOD, 1)));
    assert_false(ls_eds_mappable(must_find(LS_CO_OBJ_INTERP_PERIOD, 2)));
    assert_int_equal(uint_of(LS_CO_OBJ_CONSUMER_HB, 0, 1), 1);
    assert_int_equal(int_of(LS_CO_OBJ_QUICK_STOP_OPTION, 0, 1), 2);
}

/* ---- hand-written files ------------------------------------------------- */

#define DEVICE_INFO "[DeviceInfo]\nVendorName=Test\nVendorNumber=0x12\n"

static void test_each_access_type_reads_writes_and_maps_as_cia_306_says(void **state)
{
    (void)state;
    static const char text[] = DEVICE_INFO "[2000]\nParameterName=a\nDataType=0x0005\nAccessType=ro\nPDOMapping=1\n"
                                           "[2001]\nParameterName=b\nDataType=0x0006\nAccessType=WO\nPDOMapping=0\n"
                                           "[2002]\nParameterName=c\nDataType=0x0007\nAccessType=rw\n"
                                           "[2003]\nParameterName=d\nDataType=0x0004\nAccessType=rwr\nPDOMapping=1\n"
                                           "[2004]\nParameterName=e\nDataType=0x0003\nAccessType=rww\nPDOMapping=1\n"
                                           "[2005]\nParameterName=f\nDataType=0x0008\nAccessType=const\n";
    assert_int_equal(load_text(text), LS_OK);
    static const struct {
        uint16_t index;
        bool r, w, map;
        unsigned size;
        const char *access;
    } want[] = {
        { 0x2000, true, false, true, 1, "ro" }, { 0x2001, false, true, false, 2, "wo" },
        { 0x2002, true, true, false, 4, "rw" }, { 0x2003, true, true, true, 4, "rwr" },
        { 0x2004, true, true, true, 2, "rww" }, { 0x2005, true, false, false, 4, "const" },
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        const ls_eds_entry_t *e = must_find(want[i].index, 0);
        assert_int_equal(ls_eds_readable(e), want[i].r);
        assert_int_equal(ls_eds_writable(e), want[i].w);
        assert_int_equal(ls_eds_mappable(e), want[i].map);
        assert_int_equal(ls_eds_size(e), want[i].size);
        assert_string_equal(ls_eds_access_name(e->access), want[i].access);
        assert_int_equal(e->object_type, LS_CO_OBJECT_VAR); /* ObjectType missing: VAR */
    }
    assert_false(ls_eds_readable(NULL));
    assert_false(ls_eds_writable(NULL));
    assert_false(ls_eds_mappable(NULL));
}

static void test_numbers_are_decimal_hex_or_octal_and_may_follow_the_node_id(void **state)
{
    (void)state;
    static const char text[] = DEVICE_INFO
        "[2000]\nParameterName=dec\nDataType=0x7\nAccessType=rw\nDefaultValue=1234\n"
        "[2001]\nParameterName=hex\nDataType=0x7\nAccessType=rw\nDefaultValue=0xBEEF\n"
        "[2002]\nParameterName=oct\nDataType=0x7\nAccessType=rw\nDefaultValue=0017\n"
        "[2003]\nParameterName=neg\nDataType=0x4\nAccessType=rw\nDefaultValue=-2147483648\n"
        "[2004]\nParameterName=twos\nDataType=0x2\nAccessType=rw\nDefaultValue=0xFD\n"
        "[2005]\nParameterName=after\nDataType=0x7\nAccessType=rw\nDefaultValue=$NODEID+0x180\n"
        "[2006]\nParameterName=before\nDataType=0x7\nAccessType=rw\nDefaultValue=0x600 + $nodeid\n"
        "[2007]\nParameterName=alone\nDataType=0x5\nAccessType=rw\nDefaultValue=$NODEID\n"
        "[2008]\nParameterName=u64\nDataType=0x1B\nAccessType=rw\nDefaultValue=0xFFFFFFFFFFFFFFFF\n"
        "[2009]\nParameterName=i64\nDataType=0x15\nAccessType=rw\nDefaultValue=-9223372036854775808\n"
        "[200A]\nParameterName=real\nDataType=0x8\nAccessType=rw\nDefaultValue=-2.5e3\n"
        "[200B]\nParameterName=bool\nDataType=0x1\nAccessType=rw\nDefaultValue=1\n"
        "[200C]\nParameterName=empty\nDataType=0x7\nAccessType=rw\nDefaultValue=\n"
        "[200D]\nParameterName=zero\nDataType=0x7\nAccessType=rw\nDefaultValue=0\n"
        "[200E]\nParameterName=i24\nDataType=0x10\nAccessType=rw\nDefaultValue=0xFFFFFF\n"
        "[200F]\nParameterName=i64 rel\nDataType=0x15\nAccessType=rw\nDefaultValue=$NODEID+-9223372036854775808\n"
        "[2010]\nParameterName=i8 rel\nDataType=0x2\nAccessType=rw\nDefaultValue=$NODEID+-5\n";
    assert_int_equal(load_text(text), LS_OK);
    assert_int_equal(uint_of(0x2000, 0, 1), 1234);
    assert_int_equal(uint_of(0x2001, 0, 1), 0xBEEF);
    assert_int_equal(uint_of(0x2002, 0, 1), 15);
    assert_int_equal(int_of(0x2003, 0, 1), INT32_MIN);
    assert_int_equal(int_of(0x2004, 0, 1), -3);
    assert_int_equal(uint_of(0x2005, 0, 1), 0x181);
    assert_int_equal(uint_of(0x2005, 0, 127), 0x1FF);
    assert_true(value_of(0x2005, 0, 1).node_relative);
    assert_int_equal(uint_of(0x2006, 0, 0x23), 0x623);
    assert_int_equal(uint_of(0x2007, 0, 42), 42);
    assert_int_equal(uint_of(0x2008, 0, 1), UINT64_MAX);
    assert_int_equal(int_of(0x2009, 0, 1), INT64_MIN);
    ls_eds_value_t v = value_of(0x200A, 0, 1);
    assert_int_equal(v.kind, LS_EDS_VALUE_REAL);
    assert_true(v.r == -2500.0);
    assert_int_equal(uint_of(0x200B, 0, 1), 1);
    assert_int_equal(value_of(0x200C, 0, 1).kind, LS_EDS_VALUE_NONE);
    assert_int_equal(uint_of(0x200D, 0, 1), 0);
    assert_int_equal(int_of(0x200E, 0, 1), -1);
    assert_int_equal(int_of(0x200F, 0, 1), INT64_MIN + 1);
    assert_int_equal(int_of(0x2010, 0, 1), -4);
    assert_int_equal(int_of(0x2010, 0, 127), 122);
    /* a node id out of 1..127 is refused, the value untouched */
    ls_eds_value_t keep = { .kind = LS_EDS_VALUE_REAL, .r = 7.0 };
    v = keep;
    assert_int_equal(ls_eds_value(&g_eds, must_find(0x2005, 0), 0, &v), LS_EINVAL);
    assert_int_equal(ls_eds_value(&g_eds, must_find(0x2005, 0), 128, &v), LS_EINVAL);
    assert_int_equal(ls_eds_field(&g_eds, must_find(0x2005, 0), LS_EDS_FIELD_COUNT, 1, &v), LS_EINVAL);
    assert_true(v.kind == keep.kind && v.r == keep.r);
}

static void test_a_dcfs_parameter_value_wins_over_the_default(void **state)
{
    (void)state;
    static const char text[] =
        DEVICE_INFO "[DeviceComissioning]\nNodeID=0x22\n"
                    "[1017]\nParameterName=hb\nDataType=0x6\nAccessType=rw\nParameterValue=100\nDefaultValue=0\n"
                    "LowLimit=0\nHighLimit=65535\n"
                    "[1018]\nParameterName=id\nObjectType=0x9\nSubNumber=2\n"
                    "[1018sub0]\nParameterName=n\nDataType=0x5\nAccessType=ro\nDefaultValue=1\n"
                    "[1018sub1]\nParameterName=vendor\nDataType=0x7\nAccessType=ro\nDefaultValue=0x12\n";
    assert_int_equal(load_text(text), LS_OK);
    assert_int_equal(uint_of(0x1017, 0, 1), 100);
    assert_int_equal(field_of(0x1017, 0, LS_EDS_DEFAULT, 1).u, 0);
    assert_int_equal(field_of(0x1017, 0, LS_EDS_HIGH, 1).u, 65535);
    assert_int_equal(uint_of(0x1018, 1, 1), 0x12);
    ls_eds_device_t d;
    ls_eds_device(&g_eds, &d);
    assert_int_equal(d.dcf_node_id, 0x22);
    /* the RECORD itself is an object, not a value */
    assert_null(ls_eds_find(&g_eds, 0x1018, 2));
    assert_non_null(ls_eds_find(&g_eds, 0x1018, 0)); /* its sub 0 */
    const ls_eds_entry_t *rec = ls_eds_object(&g_eds, 0x1018);
    assert_non_null(rec);
    assert_int_equal(rec->object_type, LS_CO_OBJECT_RECORD);
    assert_int_equal(rec->sub_number, 2);
    assert_string_equal(ls_eds_name(&g_eds, rec), "id");
    assert_false(ls_eds_readable(rec));
    assert_int_equal(ls_eds_size(rec), 0);
}

static void test_sections_in_any_order_and_any_case_are_sorted_for_lookup(void **state)
{
    (void)state;
    static const char text[] = "; a comment\n# another\n\n"
                               "[2001]\r\nparametername = late ; an inline comment\r\ndatatype=0x7\r\n"
                               "accesstype=RO\r\n"
                               "  [deviceinfo]\r\n  VENDORNAME = Case\r\n"
                               "[20ab]\nParameterName=lower hex\nDataType=0x5\nAccessType=ro\n"
                               "[2000]\nParameterName: colon\nDataType: 0x5\nAccessType: ro\n"
                               "[FileInfo]\nDescription=" /* a long skipped key is cut, not refused */
                               "0123456789012345678901234567890123456789012345678901234567890123456789"
                               "0123456789012345678901234567890123456789012345678901234567890123456789"
                               "0123456789012345678901234567890123456789012345678901234567890123456789\n";
    assert_int_equal(load_text(text), LS_OK);
    assert_int_equal(ls_eds_count(&g_eds), 3);
    assert_int_equal(ls_eds_at(&g_eds, 0)->index, 0x2000);
    assert_int_equal(ls_eds_at(&g_eds, 1)->index, 0x2001);
    assert_int_equal(ls_eds_at(&g_eds, 2)->index, 0x20AB);
    assert_null(ls_eds_at(&g_eds, 3));
    assert_string_equal(ls_eds_name(&g_eds, must_find(0x2001, 0)), "late");
    assert_string_equal(ls_eds_name(&g_eds, must_find(0x2000, 0)), "colon");
    ls_eds_device_t d;
    ls_eds_device(&g_eds, &d);
    assert_string_equal(d.vendor_name, "Case");
    assert_false(d.has_vendor_number);
}

static void test_dummy_usage_adds_mappable_placeholders(void **state)
{
    (void)state;
    static const char text[] = DEVICE_INFO "[DummyUsage]\nDummy0001=0\nDummy0005=1\nDummy0007=1\n"
                                           "[1000]\nParameterName=t\nDataType=0x7\nAccessType=ro\n";
    assert_int_equal(load_text(text), LS_OK);
    assert_null(ls_eds_find(&g_eds, 1, 0));
    const ls_eds_entry_t *d5 = must_find(5, 0);
    assert_int_equal(d5->data_type, LS_CO_TYPE_UNSIGNED8);
    assert_true(ls_eds_mappable(d5));
    assert_string_equal(ls_eds_name(&g_eds, d5), "Dummy0005");
    assert_int_equal(must_find(7, 0)->data_type, LS_CO_TYPE_UNSIGNED32);
}

/* ---- refusals: one line each --------------------------------------------- */

static void test_a_file_that_is_not_an_eds_is_refused_in_one_line(void **state)
{
    (void)state;
    assert_refused("hello world\n", "t.eds:1: not an EDS or DCF: 'hello world' is neither [section], key=value nor a "
                                    "; comment");
    static const char elf[] = "\x7f"
                              "ELF\x02\x01\x01\x00\x00";
    assert_int_equal(ls_eds_load_buffer(&g_eds, "t.eds", elf, sizeof elf - 1u, g_msg, sizeof g_msg), LS_EINVAL);
    assert_string_equal(g_msg, "t.eds:1: not an EDS or DCF: a NUL byte: this is binary data, not a text file");
    assert_refused("", "t.eds: not an EDS or DCF: no [DeviceInfo] section");
    assert_refused("[Settings]\nspeed=3\n", "t.eds: not an EDS or DCF: no [DeviceInfo] section");
    assert_refused(DEVICE_INFO, "t.eds: not an EDS or DCF: no object sections ([1000], [1018sub1], ...)");
    assert_refused("key=1\n[DeviceInfo]\n", "t.eds:1: not an EDS or DCF: 'key=1': a key outside any section");
    assert_refused("[DeviceInfo\n", "t.eds:1: not an EDS or DCF: '[DeviceInfo': a section header without ']'");
    assert_refused(DEVICE_INFO "[1000] x\n", "t.eds:4: '[1000] x': text after the section header");
    assert_refused(DEVICE_INFO "[Sub]\n=3\n", "t.eds:5: [Sub]: '=3' has no key before its '='");
}

/* One VAR of `type` with `key=value`, and the line that refuses it. */
typedef struct {
    const char *type, *key, *value, *line;
} number_case_t;

static void test_a_malformed_or_misfit_number_is_refused_in_one_line(void **state)
{
    (void)state;
    static const number_case_t cases[] = {
        { "0x7", "DefaultValue", "0x12G4",
          "t.eds:8: [1000] DefaultValue: '0x12G4' is not a number: write decimal, 0x hex or 0-prefixed octal" },
        { "0x7", "DefaultValue", "09",
          "t.eds:8: [1000] DefaultValue: '09' is not a number: write decimal, 0x hex or 0-prefixed octal" },
        { "0x7", "DefaultValue", "0x",
          "t.eds:8: [1000] DefaultValue: '0x' is not a number: write decimal, 0x hex or 0-prefixed octal" },
        { "0x7", "ParameterValue", "$NODEID-1",
          "t.eds:8: [1000] ParameterValue: '$NODEID-1' is not a number: write decimal, 0x hex or 0-prefixed octal, as "
          "$NODEID+N or N+$NODEID" },
        { "0x5", "DefaultValue", "256",
          "t.eds:8: [1000] DefaultValue: '256' is too large for its data type (UNSIGNED8)" },
        { "0x6", "LowLimit", "-1",
          "t.eds:8: [1000] LowLimit: '-1' is a negative value for an unsigned type (UNSIGNED16)" },
        { "0x2", "HighLimit", "128", "t.eds:8: [1000] HighLimit: '128' is too large for its data type (INTEGER8)" },
        { "0x2", "DefaultValue", "-129",
          "t.eds:8: [1000] DefaultValue: '-129' is too small for its data type (INTEGER8)" },
        { "0x7", "DefaultValue", "0x1FFFFFFFFFFFFFFFF",
          "t.eds:8: [1000] DefaultValue: '0x1FFFFFFFFFFFFFFFF' is not a number: write decimal, 0x hex or 0-prefixed "
          "octal" },
        { "0x7", "DefaultValue", "$NODEID+0xFFFFFFFF",
          "t.eds:8: [1000] DefaultValue: '$NODEID+0xFFFFFFFF' is too large for its data type (UNSIGNED32) for some "
          "node id 1 to 127" },
        { "0x2", "DefaultValue", "$NODEID+1",
          "t.eds:8: [1000] DefaultValue: '$NODEID+1' is too large for its data type (INTEGER8) for some node id 1 to "
          "127" },
        { "0x1", "DefaultValue", "$NODEID",
          "t.eds:8: [1000] DefaultValue: '$NODEID' is too large for its data type (BOOLEAN) for some node id 1 to "
          "127" },
        { "0x5", "DefaultValue", "$NODEID+0x81",
          "t.eds:8: [1000] DefaultValue: '$NODEID+0x81' is too large for its data type (UNSIGNED8) for some node id 1 "
          "to 127" },
        { "0x8", "DefaultValue", "0x10",
          "t.eds:8: [1000] DefaultValue: '0x10' is not a finite decimal number (REAL32)" },
        { "0x8", "DefaultValue", "1e39",
          "t.eds:8: [1000] DefaultValue: '1e39' is not a finite decimal number (REAL32)" },
        { "0x7", "PDOMapping", "2", "t.eds:8: [1000] PDOMapping: '2' is not a number from 0 to 1" },
        { "0x7", "LowLimit", "10\nHighLimit=9", "t.eds:8: [1000] LowLimit: '10' is above HighLimit '9'" },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[512];
        snprintf(text, sizeof text, DEVICE_INFO "[1000]\nParameterName=x\nDataType=%s\nAccessType=rw\n%s=%s\n",
                 cases[i].type, cases[i].key, cases[i].value);
        assert_refused(text, cases[i].line);
    }
    assert_refused(DEVICE_INFO "[DeviceComissioning]\nNodeID=128\n",
                   "t.eds:5: [DeviceComissioning] NodeID: '128' is not a number from 0 to 127");
    assert_refused("[DeviceInfo]\nVendorNumber=0x1FFFFFFFF\n",
                   "t.eds:2: [DeviceInfo] VendorNumber: '0x1FFFFFFFF' is not a number from 0 to 4294967295");
}

static void test_an_unknown_access_object_or_data_type_is_refused_in_one_line(void **state)
{
    (void)state;
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nDataType=0x7\nAccessType=rx\n",
                   "t.eds:7: [1000] AccessType: unknown access type 'rx'; expected ro, wo, rw, rwr, rww or const");
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nObjectType=0x3\nDataType=0x7\nAccessType=ro\n",
                   "t.eds:6: [1000] ObjectType: 0x3 is not an object type; expected 0x7 (VAR), 0x8 (ARRAY), 0x9 "
                   "(RECORD), 0x2 (DOMAIN), 0x5 (DEFTYPE) or 0x6 (DEFSTRUCT)");
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nDataType=0x0020\nAccessType=ro\n",
                   "t.eds:6: [1000] DataType: 0x0020 is not a basic data type of CiA 301 (0x0001-0x001B); complex and "
                   "manufacturer-specific types are not supported");
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nDataType=0x0E\nAccessType=ro\n",
                   "t.eds:6: [1000] DataType: 0x000E is not a basic data type of CiA 301 (0x0001-0x001B); complex and "
                   "manufacturer-specific types are not supported");
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nAccessType=ro\n", "t.eds:4: [1000]: no DataType");
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nDataType=0x7\n", "t.eds:4: [1000]: no AccessType");
    assert_refused(DEVICE_INFO "[1000]\nDataType=0x7\nAccessType=ro\n", "t.eds:4: [1000]: no ParameterName");
    assert_refused(DEVICE_INFO "[1000]\n", "t.eds:4: [1000]: no ParameterName");
}

static void test_a_duplicate_section_or_key_is_refused_in_one_line(void **state)
{
    (void)state;
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nDataType=0x7\nAccessType=ro\n"
                               "[1000]\nParameterName=y\nDataType=0x7\nAccessType=ro\n",
                   "t.eds:8: [1000]: duplicate section (first on line 4); keep one");
    assert_refused(DEVICE_INFO "[deviceinfo]\n",
                   "t.eds:4: [deviceinfo]: duplicate section (first on line 1); keep one");
    assert_refused(DEVICE_INFO "[1000]\nParameterName=x\nDataType=0x7\nAccessType=ro\nDataType=0x5\n",
                   "t.eds:8: [1000] DataType: given twice (first on line 6); keep one");
    assert_refused("[DeviceInfo]\nVendorName=a\nVendorName=b\n",
                   "t.eds:3: [DeviceInfo] VendorName: given twice (first on line 2); keep one");
}

#define RECORD_1018(subnumber) "[1018]\nParameterName=id\nObjectType=0x9\nSubNumber=" subnumber "\n"
#define SUB(n) "[1018sub" n "]\nParameterName=s\nDataType=0x7\nAccessType=ro\n"

static void test_sub_objects_must_follow_their_object_and_match_its_sub_number(void **state)
{
    (void)state;
    assert_refused(DEVICE_INFO SUB("1"),
                   "t.eds:4: [1018sub1]: no [1018] section before it (an object's section comes first)");
    assert_refused(DEVICE_INFO "[1018]\nParameterName=v\nDataType=0x7\nAccessType=ro\n" SUB("1"),
                   "t.eds:8: [1018sub1]: [1018] (line 4) is a VAR, which has no sub-objects");
    assert_refused(DEVICE_INFO RECORD_1018("3") SUB("0") SUB("1"),
                   "t.eds:4: [1018] SubNumber: 3 sub-objects announced, 2 found");
    assert_refused(DEVICE_INFO RECORD_1018("2") SUB("1") SUB("1"),
                   "t.eds:12: [1018sub1]: duplicate section (first on line 8); keep one");
    assert_refused(DEVICE_INFO "[1018]\nParameterName=id\nObjectType=0x9\n" SUB("0"),
                   "t.eds:4: [1018]: no SubNumber (an ARRAY or RECORD names how many sub-objects follow)");
    assert_refused(DEVICE_INFO RECORD_1018("1") "[1018sub0]\nParameterName=s\nObjectType=0x9\nSubNumber=1\n",
                   "t.eds:10: [1018sub0] ObjectType: a sub-object is a VAR (0x7), not 0x9");
    assert_refused(DEVICE_INFO "[1018sub]\n",
                   "t.eds:4: [1018sub]: not an object or sub-object section ([XXXX] or [XXXXsubN], hex)");
    assert_refused(DEVICE_INFO "[1018sub100]\n",
                   "t.eds:4: [1018sub100]: not an object or sub-object section ([XXXX] or [XXXXsubN], hex)");
    assert_refused(DEVICE_INFO "[0000]\nParameterName=v\nDataType=0x7\nAccessType=ro\n",
                   "t.eds:4: [0000]: index 0x0000 is no object");
    /* a SubNumber that matches, sub-indices in hex */
    assert_int_equal(load_text(DEVICE_INFO RECORD_1018("2") SUB("0") SUB("A")), LS_OK);
    must_find(0x1018, 0x0A);
}

static void test_compact_sub_objects_are_refused_with_what_to_write_instead(void **state)
{
    (void)state;
    assert_refused(DEVICE_INFO "[1016]\nParameterName=hb\nObjectType=0x8\nDataType=0x7\nAccessType=rw\n"
                               "CompactSubObj=3\n",
                   "t.eds:9: [1016] CompactSubObj: compact sub-objects are not supported; write them out as "
                   "[1016subN] sections");
    assert_refused(DEVICE_INFO "[1016Name]\nNrOfEntries=1\n",
                   "t.eds:4: [1016Name]: compact sub-object sections are not supported; write [1016subN] sections");
}

static void test_the_caps_are_refused_naming_the_cap(void **state)
{
    (void)state;
    /* LS_EDS_MAX_ENTRIES + 1 objects */
    static char big[(LS_EDS_MAX_ENTRIES + 2u) * 64u];
    size_t n = (size_t)snprintf(big, sizeof big, "%s", DEVICE_INFO);
    for (unsigned i = 0; i <= LS_EDS_MAX_ENTRIES; i++) {
        n += (size_t)snprintf(big + n, sizeof big - n, "[%04X]\nParameterName=o\nDataType=5\nAccessType=ro\n",
                              0x2000u + i);
    }
    assert_int_equal(ls_eds_load_buffer(&g_eds, "t.eds", big, n, g_msg, sizeof g_msg), LS_EINVAL);
    char want[128];
    snprintf(want, sizeof want, "t.eds:%u: [%04X]: more than 2048 objects and sub-objects (LS_EDS_MAX_ENTRIES)",
             4u + 4u * LS_EDS_MAX_ENTRIES, 0x2000u + LS_EDS_MAX_ENTRIES);
    assert_string_equal(g_msg, want);
    assert_int_equal(ls_eds_count(&g_eds), 0);
    /* names of 150 characters: 600 of them exceed the 64 KiB of text */
    char name[151];
    memset(name, 'n', 150);
    name[150] = '\0';
    n = (size_t)snprintf(big, sizeof big, "%s", DEVICE_INFO);
    for (unsigned i = 0; i < 600u; i++) {
        n += (size_t)snprintf(big + n, sizeof big - n, "[%04X]\nParameterName=%s\nDataType=5\nAccessType=ro\n",
                              0x2000u + i, name);
    }
    assert_int_equal(ls_eds_load_buffer(&g_eds, "t.eds", big, n, g_msg, sizeof g_msg), LS_EINVAL);
    if (strstr(g_msg, "the names and texts of this file exceed 65536 bytes (LS_EDS_TEXT_BYTES)") == NULL) {
        fail_msg("%s", g_msg);
    }
    /* a line beyond LS_EDS_LINE_MAX, and a read key beyond inih's line */
    n = (size_t)snprintf(big, sizeof big, "%s[1000]\nParameterName=", DEVICE_INFO);
    memset(big + n, 'x', LS_EDS_LINE_MAX);
    n += LS_EDS_LINE_MAX;
    assert_int_equal(ls_eds_load_buffer(&g_eds, "t.eds", big, n, g_msg, sizeof g_msg), LS_EINVAL);
    assert_string_equal(g_msg, "t.eds:5: line longer than 1024 characters");
    n = (size_t)snprintf(big, sizeof big, "%s[1000]\nParameterName=%s%s\n", DEVICE_INFO, name, name);
    assert_int_equal(ls_eds_load_buffer(&g_eds, "t.eds", big, n, g_msg, sizeof g_msg), LS_EINVAL);
    assert_string_equal(g_msg, "t.eds:5: [1000] ParameterName: longer than 198 characters");
}

static void test_a_missing_file_is_an_io_error_and_empties_the_table(void **state)
{
    (void)state;
    assert_int_equal(load_text(DEVICE_INFO "[1000]\nParameterName=x\nDataType=0x7\nAccessType=ro\n"), LS_OK);
    assert_int_equal(ls_eds_count(&g_eds), 1);
    assert_int_equal(ls_eds_load(&g_eds, "/nonexistent/drive.eds", g_msg, sizeof g_msg), LS_EIO);
    assert_string_equal(g_msg, "/nonexistent/drive.eds: cannot read: No such file or directory (give the path of the "
                               "drive's EDS or DCF file)");
    assert_int_equal(ls_eds_count(&g_eds), 0);
    assert_int_equal(ls_eds_load(&g_eds, "/", g_msg, sizeof g_msg), LS_EIO);
    assert_string_equal(g_msg, "/: cannot read: Is a directory");
    assert_int_equal(ls_eds_load(NULL, "x", g_msg, sizeof g_msg), LS_EINVAL);
    assert_int_equal(ls_eds_load_buffer(&g_eds, "x", NULL, 3, g_msg, sizeof g_msg), LS_EINVAL);
    /* a message buffer too short: cut, still a C string */
    char tiny[12];
    assert_int_equal(ls_eds_load_buffer(&g_eds, "t.eds", "x\n", 2, tiny, sizeof tiny), LS_EINVAL);
    assert_string_equal(tiny, "t.eds:1: no");
    assert_int_equal(ls_eds_load_buffer(&g_eds, "t.eds", "x\n", 2, NULL, 0), LS_EINVAL);
    /* lookups on an empty table */
    assert_null(ls_eds_find(&g_eds, 0x1000, 0));
    assert_null(ls_eds_object(NULL, 0x1000));
    assert_string_equal(ls_eds_name(&g_eds, NULL), "");
}

/* Loading (inih included) and every query allocate nothing. */
static void test_loading_and_looking_up_allocate_nothing(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof path, "%s/%s", LS_VENDOR_EDS_DIR, EPOS4_DCF);
    alloc_counter_reset();
    alloc_counter_arm();
    const int r = ls_eds_load(&g_eds, path, g_msg, sizeof g_msg);
    ls_eds_value_t v;
    for (size_t i = 0; i < ls_eds_count(&g_eds); i++) {
        (void)ls_eds_value(&g_eds, ls_eds_at(&g_eds, i), 1, &v);
    }
    (void)ls_eds_find(&g_eds, 0x1018, 1);
    (void)load_text("[1000]\nbad\n");
    alloc_counter_disarm();
    assert_int_equal(r, LS_OK);
    assert_int_equal(alloc_counter_count(), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_epos4_dcf_loads_with_its_identity),
        cmocka_unit_test(test_the_epos4_dcf_keeps_node_1s_absolute_cob_ids),
        cmocka_unit_test(test_every_epos4_pdo_is_valid_and_synchronous_with_its_power_on_mapping),
        cmocka_unit_test(test_the_epos4_dcf_has_the_402_objects_and_lacks_what_its_readme_says),
        cmocka_unit_test(test_the_ros2_canopen_eds_loads_with_its_identity),
        cmocka_unit_test(test_the_ros2_canopen_eds_has_its_quirks),
        cmocka_unit_test(test_each_access_type_reads_writes_and_maps_as_cia_306_says),
        cmocka_unit_test(test_numbers_are_decimal_hex_or_octal_and_may_follow_the_node_id),
        cmocka_unit_test(test_a_dcfs_parameter_value_wins_over_the_default),
        cmocka_unit_test(test_sections_in_any_order_and_any_case_are_sorted_for_lookup),
        cmocka_unit_test(test_dummy_usage_adds_mappable_placeholders),
        cmocka_unit_test(test_a_file_that_is_not_an_eds_is_refused_in_one_line),
        cmocka_unit_test(test_a_malformed_or_misfit_number_is_refused_in_one_line),
        cmocka_unit_test(test_an_unknown_access_object_or_data_type_is_refused_in_one_line),
        cmocka_unit_test(test_a_duplicate_section_or_key_is_refused_in_one_line),
        cmocka_unit_test(test_sub_objects_must_follow_their_object_and_match_its_sub_number),
        cmocka_unit_test(test_compact_sub_objects_are_refused_with_what_to_write_instead),
        cmocka_unit_test(test_the_caps_are_refused_naming_the_cap),
        cmocka_unit_test(test_a_missing_file_is_an_io_error_and_empties_the_table),
        cmocka_unit_test(alloc_counter_test_sees_malloc),
        cmocka_unit_test(test_loading_and_looking_up_allocate_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
