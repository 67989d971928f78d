"""The Python module's benchmark rows (docs/performance.md, docs/python.md): register accesses
per second from Python, and 1 000 Data_Exchange cycles driven from Python against the same run in
C++ (dpc31_bench's BM_DataExchange at 1.5 Mbaud, 4 + 4 bytes, block copies: the same session,
built-in responder with Res_User_WD), as a ratio.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py build/bin/dpc31_bench
Prints one line per row and exits 0; a session that does not reach Data_Exchange exits 1."""

import json
import subprocess
import sys
import time

import dpc31


def best_of(runs, fn):
    return min(fn() for _ in range(runs))


def reads_per_second(n=200_000):
    chip = dpc31.Chip("dpc31")
    addr = chip.addr_of("R_TS_Adr")  # a RAM cell: a plain bus access of 4 clocks

    def run():
        t0 = time.perf_counter()
        for _ in range(n):
            chip.read(addr)
        return time.perf_counter() - t0

    return n / best_of(3, run)


def python_data_exchange(n=1000):
    def run():
        chip = dpc31.Chip("dpc31")
        chip_cfg = dpc31.SlaveConfig(in_len=4, out_len=4)
        master = dpc31.Master(chip, baud=1_500_000, slave=chip_cfg)
        user = master.run_responder(inputs=b"\x5a" * 4, user_watchdog=True)
        if not master.startup(5000):
            sys.exit("bench_python: no Data_Exchange")
        out = b"\x11" * 4
        t0 = time.perf_counter()
        for _ in range(n):
            if master.data_exchange(out).answer is None:
                sys.exit("bench_python: a Data_Exchange was not answered")
            master.clear_history()
        elapsed = time.perf_counter() - t0
        del user
        return elapsed

    return best_of(3, run)


def cpp_data_exchange(bench, n=1000):
    out = subprocess.run(
        [bench, "--benchmark_filter=^BM_DataExchange/baud:1500000/len:4/block:1/real_time$",
         "--benchmark_format=json", "--benchmark_repetitions=3"],
        check=True, capture_output=True, text=True).stdout
    runs = [b for b in json.loads(out)["benchmarks"] if b.get("run_type") == "iteration"]
    per = min(b["real_time"] for b in runs)  # ns per Data_Exchange
    assert runs[0]["time_unit"] == "ns"
    return per * n / 1e9


def main():
    reads = reads_per_second()
    py = python_data_exchange()
    cpp = cpp_data_exchange(sys.argv[1])
    print(f"python register reads: {reads:.3g} per second")
    print(f"1000 Data_Exchange from Python: {py * 1e3:.1f} ms")
    print(f"1000 Data_Exchange in C++ (BM_DataExchange): {cpp * 1e3:.1f} ms")
    print(f"ratio Python / C++: {py / cpp:.2f}")


if __name__ == "__main__":
    main()
