/*
 * string.h - the few string and memory functions bare-metal robosoc programs may use.
 *
 * Only core (RISC-V) builds see this header; host builds use the host's own.  The
 * implementations are in libc/string.c, linked into every core program (unused ones are
 * removed by --gc-sections).
 */
#ifndef HF_LIBC_STRING_H
#define HF_LIBC_STRING_H

#include <stddef.h>

void *memcpy(void *restrict dst, const void *restrict src, size_t n);
void *memmove(void *dst, const void *src, size_t n);
void *memset(void *dst, int c, size_t n);
int memcmp(const void *a, const void *b, size_t n);
size_t strlen(const char *s);
int strcmp(const char *a, const char *b);
int strncmp(const char *a, const char *b, size_t n);
char *strcpy(char *restrict dst, const char *restrict src);

#endif /* HF_LIBC_STRING_H */
