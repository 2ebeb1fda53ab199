/* The fuzz input as a file, for the parsers that read a path (configuration
 * and robot model files): one memfd per process, rewritten with each input
 * and seen through /proc/self/fd, exactly as a path on disk. */
#ifndef FUZZ_FILE_H
#define FUZZ_FILE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/mman.h>
#include <unistd.h>

/* The path of a file holding data[0..size). Static storage; traps when the
 * memfd cannot be made or written (the harness is broken, not the input). */
static inline const char *fuzz_input_file(const uint8_t *data, size_t size)
{
    static int fd = -1;
    static char path[64];
    if (fd < 0) {
        fd = memfd_create("ls-fuzz-input", 0);
        if (fd < 0) {
            __builtin_trap();
        }
        snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    }
    if (ftruncate(fd, 0) != 0 || lseek(fd, 0, SEEK_SET) != 0) {
        __builtin_trap();
    }
    for (size_t done = 0; done < size;) {
        ssize_t w = write(fd, data + done, size - done);
        if (w <= 0) {
            __builtin_trap();
        }
        done += (size_t)w;
    }
    return path;
}

#endif
