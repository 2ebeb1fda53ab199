/* The EDS/DCF parser (firmware/app/ls_eds.c, inih underneath): any bytes
 * either load into a table that keeps its invariants, or are refused with
 * one line and an empty table; never a crash, a hang or an unterminated
 * string. Each input is read twice, from memory (ls_eds_load_buffer) and
 * as a file in 4 KiB pieces (ls_eds_load on a memfd seen through
 * /proc/self/fd), and both readings must agree. */
#define _GNU_SOURCE
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "ls_canopen.h"
#include "ls_eds.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static ls_eds_t g_mem;
static ls_eds_t g_file;

#define CHECK(cond)                                                                                                    \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            __builtin_trap();                                                                                          \
        }                                                                                                              \
    } while (0)

static void check_line(const char *msg, size_t cap)
{
    CHECK(memchr(msg, '\0', cap) != NULL);
    CHECK(msg[0] != '\0');            /* an error says what is wrong */
    CHECK(strchr(msg, '\n') == NULL); /* in one line */
}

static uint32_t key_of(const ls_eds_entry_t *e)
{
    return ((uint32_t)e->index << 9) | (e->is_sub ? (uint32_t)e->sub + 1u : 0u);
}

static void check_value(const ls_eds_t *eds, const ls_eds_entry_t *e, int field, uint8_t node)
{
    ls_eds_value_t v;
    CHECK(ls_eds_field(eds, e, (ls_eds_field_id_t)field, node, &v) == LS_OK);
    CHECK(v.text != NULL);
    if (v.kind == LS_EDS_VALUE_TEXT) {
        CHECK(v.text >= eds->text && v.text < eds->text + eds->text_used);
        CHECK(strlen(v.text) < (size_t)(eds->text + eds->text_used - v.text));
    }
    if (v.kind == LS_EDS_VALUE_UINT && e->data_type != LS_CO_TYPE_UNSIGNED64 && ls_eds_size(e) > 0u) {
        const unsigned bits = e->data_type == LS_CO_TYPE_BOOLEAN ? 1u : 8u * ls_eds_size(e);
        CHECK(v.u >> bits == 0u); /* fits its type, $NODEID included */
    }
}

static void check_table(const ls_eds_t *eds)
{
    const size_t n = ls_eds_count(eds);
    CHECK(n > 0u && n <= LS_EDS_MAX_ENTRIES);
    CHECK(eds->text_used <= LS_EDS_TEXT_BYTES);
    ls_eds_device_t d;
    CHECK(ls_eds_device(eds, &d) == LS_OK);
    CHECK(d.vendor_name != NULL && d.product_name != NULL);
    for (size_t i = 0; i < n; i++) {
        const ls_eds_entry_t *e = ls_eds_at(eds, i);
        CHECK(e != NULL);
        CHECK(i == 0u || key_of(ls_eds_at(eds, i - 1u)) < key_of(e)); /* sorted, no duplicates */
        const char *name = ls_eds_name(eds, e);                       /* may be "": ParameterName= is accepted */
        CHECK(name == eds->text || (name > eds->text && name < eds->text + eds->text_used && name[-1] == '\0'));
        if (e->data_type == 0u) { /* ARRAY, RECORD, DEFSTRUCT: their sub-objects follow */
            CHECK(!e->is_sub && e->access == LS_EDS_ACCESS_NONE);
            CHECK(ls_eds_object(eds, e->index) == e);
            CHECK(!ls_eds_readable(e) && !ls_eds_writable(e) && !ls_eds_mappable(e));
            size_t subs = 0u;
            while (i + 1u + subs < n && ls_eds_at(eds, i + 1u + subs)->index == e->index) {
                subs++;
            }
            CHECK(subs == e->sub_number);
            continue;
        }
        CHECK(ls_co_type_name(e->data_type) != NULL);
        CHECK(e->access >= LS_EDS_RO && e->access <= LS_EDS_CONST);
        CHECK(ls_eds_access_name(e->access)[0] != '\0');
        CHECK(ls_eds_find(eds, e->index, e->sub) == e);
        if (e->is_sub) {
            const ls_eds_entry_t *parent = ls_eds_object(eds, e->index);
            CHECK(parent != NULL && parent->data_type == 0u);
        }
        for (int f = 0; f < LS_EDS_FIELD_COUNT; f++) {
            check_value(eds, e, f, LS_CO_NODE_MIN);
            check_value(eds, e, f, LS_CO_NODE_MAX);
        }
        ls_eds_value_t v;
        CHECK(ls_eds_value(eds, e, 0x40, &v) == LS_OK);
        CHECK(ls_eds_value(eds, e, 0, &v) == LS_EINVAL);
    }
}

/* Field by field: the structs' padding is not part of the table. */
static bool same_entry(const ls_eds_entry_t *a, const ls_eds_entry_t *b)
{
    if (a->index != b->index || a->sub != b->sub || a->is_sub != b->is_sub || a->object_type != b->object_type ||
        a->access != b->access || a->pdo_mapping != b->pdo_mapping || a->sub_number != b->sub_number ||
        a->data_type != b->data_type || a->line != b->line || a->name != b->name) {
        return false;
    }
    for (int f = 0; f < LS_EDS_FIELD_COUNT; f++) {
        if (a->kind[f] != b->kind[f] || a->bits[f] != b->bits[f]) {
            return false;
        }
    }
    return true;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int fd = -1;
    static char path[64];
    if (fd < 0) {
        fd = memfd_create("ls-eds-fuzz", 0);
        CHECK(fd >= 0);
        snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    }
    CHECK(ftruncate(fd, 0) == 0 && lseek(fd, 0, SEEK_SET) == 0);
    for (size_t done = 0; done < size;) {
        ssize_t w = write(fd, data + done, size - done);
        CHECK(w > 0);
        done += (size_t)w;
    }

    char msg_mem[LS_EDS_MSG_MAX];
    char msg_file[LS_EDS_MSG_MAX];
    const int r_mem = ls_eds_load_buffer(&g_mem, path, (const char *)data, size, msg_mem, sizeof msg_mem);
    const int r_file = ls_eds_load(&g_file, path, msg_file, sizeof msg_file);
    CHECK(r_mem == r_file);
    CHECK(strcmp(msg_mem, msg_file) == 0);
    CHECK(ls_eds_count(&g_mem) == ls_eds_count(&g_file));
    if (r_mem != LS_OK) {
        CHECK(r_mem == LS_EINVAL);
        check_line(msg_mem, sizeof msg_mem);
        CHECK(ls_eds_count(&g_mem) == 0u);
        return 0;
    }
    CHECK(msg_mem[0] == '\0');
    for (size_t i = 0; i < ls_eds_count(&g_mem); i++) {
        CHECK(same_entry(ls_eds_at(&g_mem, i), ls_eds_at(&g_file, i)));
    }
    CHECK(g_mem.text_used == g_file.text_used && memcmp(g_mem.text, g_file.text, g_mem.text_used) == 0);
    check_table(&g_mem);
    return 0;
}
