// ARM semihosting calls (ARM's "Semihosting for AArch32 and AArch64", SYS_* numbers): a
// BKPT 0xAB with the operation in r0 and its argument block in r1; QEMU's -semihosting
// answers them from the host's files and terminal.
#include <string.h>
#include "semihost.h"

#define SYS_OPEN 0x01
#define SYS_CLOSE 0x02
#define SYS_WRITE 0x05
#define SYS_READ 0x06
#define SYS_FLEN 0x0C
#define SYS_GET_CMDLINE 0x15
#define SYS_EXIT 0x18
#define SYS_EXIT_EXTENDED 0x20
#define ADP_STOPPED_APPLICATION_EXIT 0x20026

static int sh_call(int op, void *arg) {
    register int r0 __asm__("r0") = op;
    register void *r1 __asm__("r1") = arg;
    __asm__ volatile ("bkpt 0xAB" : "+r" (r0) : "r" (r1) : "memory");
    return r0;
}

int sh_open(const char *name, int mode) {
    uint32_t a[3] = {(uint32_t)name, (uint32_t)mode, (uint32_t)strlen(name)};
    return sh_call(SYS_OPEN, a);
}

int sh_close(int fd) {
    uint32_t a[1] = {(uint32_t)fd};
    return sh_call(SYS_CLOSE, a);
}

int sh_write(int fd, const void *buf, size_t len) {
    uint32_t a[3] = {(uint32_t)fd, (uint32_t)buf, (uint32_t)len};
    return sh_call(SYS_WRITE, a);  // the bytes NOT written
}

int sh_read(int fd, void *buf, size_t len) {
    uint32_t a[3] = {(uint32_t)fd, (uint32_t)buf, (uint32_t)len};
    return sh_call(SYS_READ, a);  // the bytes NOT read
}

int sh_flen(int fd) {
    uint32_t a[1] = {(uint32_t)fd};
    return sh_call(SYS_FLEN, a);
}

int sh_cmdline(char *buf, size_t len) {
    uint32_t a[2] = {(uint32_t)buf, (uint32_t)len};
    return sh_call(SYS_GET_CMDLINE, a);
}

void sh_exit(int code) {
    uint32_t a[2] = {ADP_STOPPED_APPLICATION_EXIT, (uint32_t)code};
    sh_call(SYS_EXIT_EXTENDED, a);
    sh_call(SYS_EXIT, (void *)ADP_STOPPED_APPLICATION_EXIT);
    for (;;) {
    }
}

static int out_fd = -1;

void sh_out(const char *s, size_t len) {
    if (out_fd < 0) {
        out_fd = sh_open(":tt", 4);  // ":tt" opened for writing: the host's stdout
    }
    sh_write(out_fd, s, len);
}
