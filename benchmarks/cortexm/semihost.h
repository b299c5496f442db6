// ARM semihosting (the debugger's, here QEMU's): the board's only link to the host.
#ifndef DXB_SEMIHOST_H
#define DXB_SEMIHOST_H
#include <stddef.h>
#include <stdint.h>

int sh_open(const char *name, int mode);
int sh_close(int fd);
int sh_write(int fd, const void *buf, size_t len);
int sh_read(int fd, void *buf, size_t len);
int sh_flen(int fd);
int sh_cmdline(char *buf, size_t len);
void sh_exit(int code) __attribute__((noreturn));
void sh_out(const char *s, size_t len);

#endif
