/* ls_eds_dump FILE NODE: every object of an EDS/DCF as ls_eds reads it for
 * node id NODE, one line each, for people and for test_eds_vs_canopen.py:
 *
 *   # device vendor_name="maxon motor ag" vendor_number=0xFB ...
 *   0x1018 RECORD - - map=0 subnumber=5 name="Identity Object"
 *   0x1018:01 VAR UNSIGNED32 ro map=0 size=4 value=0xFB default=0xFB param=- low=- high=- name="Vendor ID"
 *
 * value is what the drive holds at power-on (ParameterValue, else
 * DefaultValue), resolved for NODE, and nodeid= lists the fields written
 * with $NODEID; signed integers are decimal, unsigned
 * ones hex, reals %.17g, texts double-quoted with \" and \\ escaped; "-"
 * when the file gives none. Exit 0, 1 when the file is refused (its one
 * line on stderr), 2 on a usage error. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ls_canopen.h"
#include "ls_eds.h"

static ls_eds_t g_eds; /* about 180 KiB: static, as the header asks */

static void print_text(const char *s)
{
    putchar('"');
    for (; *s != '\0'; s++) {
        if (*s == '"' || *s == '\\') {
            putchar('\\');
        }
        putchar(*s);
    }
    putchar('"');
}

static void print_value(const ls_eds_value_t *v)
{
    switch (v->kind) {
    case LS_EDS_VALUE_INT: printf("%lld", (long long)v->i); break;
    case LS_EDS_VALUE_UINT: printf("0x%llX", (unsigned long long)v->u); break;
    case LS_EDS_VALUE_REAL: printf("%.17g", v->r); break;
    case LS_EDS_VALUE_TEXT: print_text(v->text); break;
    case LS_EDS_VALUE_NONE:
    default: putchar('-'); break;
    }
}

static const char *object_name(uint8_t object_type)
{
    switch (object_type) {
    case LS_CO_OBJECT_VAR: return "VAR";
    case LS_CO_OBJECT_ARRAY: return "ARRAY";
    case LS_CO_OBJECT_RECORD: return "RECORD";
    case LS_CO_OBJECT_DOMAIN: return "DOMAIN";
    case LS_CO_OBJECT_DEFTYPE: return "DEFTYPE";
    case LS_CO_OBJECT_DEFSTRUCT: return "DEFSTRUCT";
    default: return "?";
    }
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: ls_eds_dump FILE NODE (NODE: the node id 1-127 that $NODEID stands for)\n");
        return 2;
    }
    char *end = NULL;
    const long node = strtol(argv[2], &end, 0);
    if (end == argv[2] || *end != '\0' || node < (long)LS_CO_NODE_MIN || node > (long)LS_CO_NODE_MAX) {
        fprintf(stderr, "ls_eds_dump: NODE '%s' is not a node id: give 1 to 127\n", argv[2]);
        return 2;
    }
    char msg[LS_EDS_MSG_MAX];
    if (ls_eds_load(&g_eds, argv[1], msg, sizeof msg) != LS_OK) {
        fprintf(stderr, "%s\n", msg);
        return 1;
    }
    ls_eds_device_t d;
    (void)ls_eds_device(&g_eds, &d);
    printf("# device vendor_name=");
    print_text(d.vendor_name);
    printf(" product_name=");
    print_text(d.product_name);
    if (d.has_vendor_number) {
        printf(" vendor_number=0x%X", (unsigned)d.vendor_number);
    }
    if (d.has_product_number) {
        printf(" product_number=0x%X", (unsigned)d.product_number);
    }
    if (d.has_revision_number) {
        printf(" revision_number=0x%X", (unsigned)d.revision_number);
    }
    if (d.dcf_node_id != 0u) {
        printf(" dcf_node_id=%u", (unsigned)d.dcf_node_id);
    }
    printf(" entries=%zu\n", ls_eds_count(&g_eds));
    for (size_t i = 0; i < ls_eds_count(&g_eds); i++) {
        const ls_eds_entry_t *e = ls_eds_at(&g_eds, i);
        if (e->is_sub) {
            printf("0x%04X:%02X ", (unsigned)e->index, (unsigned)e->sub);
        } else {
            printf("0x%04X ", (unsigned)e->index);
        }
        const char *type = ls_co_type_name(e->data_type);
        const char *access = ls_eds_access_name(e->access);
        printf("%s %s %s map=%d", object_name(e->object_type), type != NULL ? type : "-",
               access[0] != '\0' ? access : "-", ls_eds_mappable(e) ? 1 : 0);
        if (e->data_type == 0u) {
            printf(" subnumber=%u", (unsigned)e->sub_number);
        } else {
            printf(" size=%u", ls_eds_size(e));
            static const struct {
                const char *key;
                int field; /* -1: the power-on value */
            } cols[] = { { "value", -1 },
                         { "default", LS_EDS_DEFAULT },
                         { "param", LS_EDS_PARAMETER },
                         { "low", LS_EDS_LOW },
                         { "high", LS_EDS_HIGH } };
            for (size_t k = 0; k < sizeof cols / sizeof cols[0]; k++) {
                ls_eds_value_t v;
                const int r = cols[k].field < 0
                                  ? ls_eds_value(&g_eds, e, (uint8_t)node, &v)
                                  : ls_eds_field(&g_eds, e, (ls_eds_field_id_t)cols[k].field, (uint8_t)node, &v);
                printf(" %s=", cols[k].key);
                if (r == LS_OK) {
                    print_value(&v);
                } else {
                    putchar('?');
                }
            }
            /* the fields written with $NODEID */
            const char *sep = " nodeid=";
            for (size_t k = 1; k < sizeof cols / sizeof cols[0]; k++) {
                ls_eds_value_t v;
                if (ls_eds_field(&g_eds, e, (ls_eds_field_id_t)cols[k].field, (uint8_t)node, &v) == LS_OK &&
                    v.node_relative) {
                    printf("%s%s", sep, cols[k].key);
                    sep = ",";
                }
            }
        }
        printf(" name=");
        print_text(ls_eds_name(&g_eds, e));
        putchar('\n');
    }
    return ferror(stdout) ? 1 : 0;
}
