/* The checks of fst_hooks.h. */
#include "fst_hooks.h"

#include <errno.h>
#include <sys/stat.h>

static unsigned long failures;
static int last_errno;

static void count(int err) {
  __atomic_add_fetch(&failures, 1, __ATOMIC_SEQ_CST);
  if (err != 0) __atomic_store_n(&last_errno, err, __ATOMIC_SEQ_CST);
}

int dpc31_fst_fclose(FILE* f) {
  if (f == NULL) return EOF;
  const int failed_before = ferror(f);
  errno = 0;
  const int rc = fclose(f);
  if (rc != 0) {
    count(errno);
  } else if (failed_before) {
    count(0);
  }
  return rc;
}

int dpc31_fst_gzclose(gzFile f) {
  const int rc = gzclose(f);
  if (rc != Z_OK) count(rc == Z_ERRNO ? errno : 0);
  return rc;
}

void* dpc31_fst_mmap(void* addr, size_t len, int prot, int flags, int fd, off_t off) {
  struct stat st;
  if (fd >= 0 && fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && off >= 0 &&
      (unsigned long long)st.st_size < (unsigned long long)off + len) {
    count(0);
    return mmap(addr, len, prot, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  }
  return mmap(addr, len, prot, flags, fd, off);
}

unsigned long dpc31_fst_failed_writes(void) { return __atomic_load_n(&failures, __ATOMIC_SEQ_CST); }

int dpc31_fst_last_errno(void) { return __atomic_load_n(&last_errno, __ATOMIC_SEQ_CST); }
