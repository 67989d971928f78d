#!/usr/bin/env python3
"""Random straight-line-and-forward-branch MCS-51 programs for the ucsim cross-check
(docs/cpu.md): every instruction of the ALU, data transfer, bit and branch groups with random
operands, seeded, so each build writes the same programs. Usage: gen_programs.py OUTDIR COUNT."""
import random
import sys

DIRECT_RAM = list(range(0x20, 0x7F))  # 7Fh is the loop counter
# ACC, B, DPL, DPH. PSW only through MOV PSW,#data and its bits: s51 leaves P stale after some
# writes to A, and a program reading PSW as a byte would carry that into A (docs/cpu.md).
SFRS = [0xE0, 0xF0, 0x82, 0x83]
BITS = list(range(0x00, 0x80)) + list(range(0xE0, 0xE8)) + list(range(0xF0, 0xF8)) + \
    [0xD1, 0xD2, 0xD5, 0xD6, 0xD7]  # PSW: F1, OV, F0, AC, CY (RS0/RS1 and P apart)


def direct(r):
    return r.choice(DIRECT_RAM) if r.random() < 0.8 else r.choice(SFRS)


def src(r):
    """A source operand of ADD/ADDC/SUBB/ANL/ORL/XRL/MOV A,..."""
    k = r.randrange(4)
    if k == 0:
        return [], f"#0x{r.randrange(256):02x}"
    if k == 1:
        return [], f"0x{direct(r):02x}"
    if k == 2:
        i = r.randrange(2)
        return [f"mov r{i},#0x{r.randrange(0x20, 0xC0):02x}"], f"@r{i}"
    return [], f"r{r.randrange(8)}"


def unit(r, labels, subs):
    """One unit: a few lines, possibly a forward branch (label placed later)."""
    k = r.randrange(40)
    if k < 6:
        pre, s = src(r)
        op = r.choice(["add", "addc", "subb", "anl", "orl", "xrl"])
        return pre + [f"{op} a,{s}"]
    if k < 8:
        op = r.choice(["anl", "orl", "xrl"])
        d = direct(r)
        return [f"{op} 0x{d:02x},a"] if r.random() < 0.5 else [f"{op} 0x{d:02x},#0x{r.randrange(256):02x}"]
    if k < 10:
        op = r.choice(["inc", "dec"])
        pre, s = src(r)
        if s.startswith("#"):
            s = "a"
        return pre + [f"{op} {s}"]
    if k < 12:
        return [r.choice(["rl a", "rlc a", "rr a", "rrc a", "swap a", "cpl a", "clr a", "da a",
                          "mul ab", "div ab", "inc dptr", "nop", "cpl c", "clr c", "setb c"])]
    if k < 16:
        pre, s = src(r)
        d = r.randrange(4)
        if d == 0:
            return pre + [f"mov a,{s}"]
        if d == 1 and not s.startswith("@") and not s.startswith("r"):
            return [f"mov 0x{direct(r):02x},{s}"]
        if d == 2:
            return [f"mov r{r.randrange(8)},#0x{r.randrange(256):02x}",
                    f"mov r{r.randrange(8)},0x{direct(r):02x}", f"mov r{r.randrange(8)},a"]
        i = r.randrange(2)
        return [f"mov r{i},#0x{r.randrange(0x20, 0xC0):02x}",
                r.choice([f"mov @r{i},a", f"mov @r{i},#0x{r.randrange(256):02x}",
                          f"mov @r{i},0x{direct(r):02x}", f"mov 0x{direct(r):02x},@r{i}",
                          f"xchd a,@r{i}", f"xch a,@r{i}"])]
    if k < 18:
        return [r.choice([f"xch a,r{r.randrange(8)}", f"xch a,0x{direct(r):02x}",
                          f"mov 0x{direct(r):02x},r{r.randrange(8)}", f"mov 0x{direct(r):02x},a",
                          f"mov dptr,#0x{r.randrange(65536):04x}"])]
    if k < 21:
        b = r.choice(BITS)
        return [r.choice([f"setb 0x{b:02x}", f"clr 0x{b:02x}", f"cpl 0x{b:02x}", f"mov c,0x{b:02x}",
                          f"mov 0x{b:02x},c", f"anl c,0x{b:02x}", f"anl c,/0x{b:02x}",
                          f"orl c,0x{b:02x}", f"orl c,/0x{b:02x}"])]
    if k < 22:
        return [f"push 0x{direct(r):02x}", f"pop 0x{direct(r):02x}"]
    if k < 23:
        return [r.choice(["mov dptr,#table", "mov dptr,#0x0f00"]), "movc a,@a+dptr"] if r.random() < 0.7 \
            else ["movc a,@a+pc"]
    if k < 25:
        i = r.randrange(2)
        return [f"mov p2,#0x{r.randrange(256):02x}", f"mov r{i},#0x{r.randrange(256):02x}",
                r.choice([f"movx @r{i},a", f"movx a,@r{i}"])] if r.random() < 0.5 else \
            [f"mov dptr,#0x{r.randrange(65536):04x}", r.choice(["movx @dptr,a", "movx a,@dptr"])]
    if k < 26:
        return [f"mov psw,#0x{r.randrange(256):02x}"]
    if k < 28:
        name = f"s{len(subs)}"
        subs.append(name)
        return [f"{r.choice(['acall', 'lcall'])} {name}"]
    if k < 29:  # a short backward loop on the counter at 7Fh
        name = f"b{len(labels)}x"
        labels.append(None)
        pre, s = src(r)
        return [f"mov 0x7f,#0x{r.randrange(1, 5):02x}", f"{name}:"] + pre + [f"add a,{s}", f"djnz 0x7f,{name}"]
    # A forward branch over 1..3 units.
    name = f"f{len(labels)}"
    labels.append((name, r.randrange(1, 4)))
    b = r.choice(BITS)
    form = r.choice([f"jz {name}", f"jnz {name}", f"jc {name}", f"jnc {name}", f"jb 0x{b:02x},{name}",
                     f"jnb 0x{b:02x},{name}", f"jbc 0x{b:02x},{name}", f"sjmp {name}", f"ajmp {name}",
                     f"ljmp {name}", f"cjne a,#0x{r.randrange(256):02x},{name}",
                     f"cjne a,0x{direct(r):02x},{name}",
                     f"cjne r{r.randrange(8)},#0x{r.randrange(256):02x},{name}",
                     f"djnz r{r.randrange(8)},{name}", f"djnz 0x{r.choice(DIRECT_RAM):02x},{name}"])
    if form.startswith("cjne @"):
        return [form]
    if r.random() < 0.2:
        i = r.randrange(2)
        return [f"mov r{i},#0x{r.randrange(0x20, 0xC0):02x}", f"cjne @r{i},#0x{r.randrange(256):02x},{name}"]
    return [form]


def program(seed):
    r = random.Random(seed)
    lines = ["\t.area CSEG (ABS,CODE)", "\t.org 0", "\tljmp start", "\t.org 0x100", "start:",
             "\tmov sp,#0xbf"]
    for reg in range(0x20, 0x80, 1):
        if r.random() < 0.3:
            lines.append(f"\tmov 0x{reg:02x},#0x{r.randrange(256):02x}")
    labels, subs = [], []
    pending = []  # [label, units left]
    for _ in range(r.randrange(120, 180)):
        body = unit(r, labels, subs)
        for text in body:
            lines.append(text if text.endswith(":") else "\t" + text)
        if labels and labels[-1] is not None and isinstance(labels[-1], tuple) and \
                any(t.endswith(labels[-1][0]) for t in body):
            pending.append([labels[-1][0], labels[-1][1]])
            labels[-1] = None
        for p in pending:
            p[1] -= 1
        for p in [p for p in pending if p[1] < 0]:
            lines.append(f"{p[0]}:")
            pending.remove(p)
    for p in pending:
        lines.append(f"{p[0]}:")
    lines.append("halt:\tsjmp halt")
    for name in subs:
        lines.append(f"{name}:")
        for _ in range(r.randrange(1, 4)):
            body = unit(r, [None], [])
            if any(t.split()[0] in ("acall", "lcall") or t.endswith(":") or "djnz 0x7f" in t or
                   t.split()[0] in ("jz", "jnz", "jc", "jnc", "jb", "jnb", "jbc", "sjmp", "ajmp",
                                    "ljmp", "cjne", "djnz") for t in body):
                body = ["nop"]
            lines += ["\t" + t for t in body]
        lines.append("\tret")
    lines.append("table:")
    for i in range(0, 256, 16):
        lines.append("\t.db " + ",".join(f"0x{r.randrange(256):02x}" for _ in range(16)))
    return "\n".join(lines) + "\n"


def main():
    out, count = sys.argv[1], int(sys.argv[2])
    for seed in range(count):
        with open(f"{out}/random{seed:02d}.asm", "w", encoding="ascii") as f:
            f.write(program(seed))


if __name__ == "__main__":
    main()
