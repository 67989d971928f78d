/* fstapi (from Debian's verilator package) checks none of its writes: a value-change block whose
 * scratch file (tmpfile() in /tmp) could not be written goes into a well-formed FST with wrong
 * values, and a scratch or .hier file shorter than fstapi believes is mmap()ed past its end:
 * SIGBUS at the first access. Every copy of fstapi we compile (lib/wavediff/fstapi_all.c, and
 * Verilator's verilated_fst_c.cpp in dpc31_rtl) includes this header first with
 * DPC31_FST_HOOK_CALLS defined, so that its fclose, gzclose and mmap go through the checks below;
 * OutFile::commit_fst() refuses an FST written while dpc31_fst_failed_writes() grew
 * (docs/bad-input.md, "Output files"). C and C++. */
#ifndef DPC31_FST_HOOKS_H
#define DPC31_FST_HOOKS_H

#ifdef __cplusplus
/* <cstdio> #undefs fclose: included first, it does so before the macro below exists. */
#include <cstdio>
#else
#include <stdio.h>
#endif
#include <sys/mman.h>
#include <sys/types.h>
#include <zlib.h>

#ifdef __cplusplus
extern "C" {
#endif

/* fclose() that counts a failure when the stream's error flag is set (a write that failed since
 * it was opened: fstapi goes on after one) or the final flush fails. */
int dpc31_fst_fclose(FILE* f);
/* gzclose() (the hierarchy's compression writes through its own descriptor) that counts a
 * failure when the last write fails. */
int dpc31_fst_gzclose(gzFile f);
/* mmap() of a file: one shorter than the range asked for (its writes failed) counts a failure
 * and maps anonymous memory instead, so fstapi finishes (its file is refused) without SIGBUS. */
void* dpc31_fst_mmap(void* addr, size_t len, int prot, int flags, int fd, off_t off);
/* How many failures the three have counted in this process, in any thread (Verilator's tracer
 * may write in a thread of its own): a writer compares it before and after its file. */
unsigned long dpc31_fst_failed_writes(void);
/* The errno of the last counted failure that had one (0: none known). */
int dpc31_fst_last_errno(void);

#ifdef __cplusplus
}
#endif

#ifdef DPC31_FST_HOOK_CALLS
#define fclose dpc31_fst_fclose
#define gzclose dpc31_fst_gzclose
#define mmap dpc31_fst_mmap
#endif

#endif
