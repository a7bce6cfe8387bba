"""Random PLC *source* programs, for running real compiler output on both VM
backends: procedures calling each other, if/else, do-while and while loops,
&& || ! ~ - % ^ << >>, every builtin, messages, prints and exits."""

from __future__ import annotations

import random

_VARS = ["a", "b", "c", "d", "e"]
_READ = _VARS + ["eparam", "timer", "proc", "var00", "var01", "vexit", "adc01"]
_OPS = ["+", "-", "*", "/", "%", "&", "|", "^", "<<", ">>", "==", "!=", "<", "<=", ">", ">=",
        "&&", "||"]
_CONSTS = ["0", "1", "2", "3", "7", "31", "32", "100", "0x7fffffff", "0xffffffff", "1000",
           "0x80000000", "65535"]


class _Src:
    def __init__(self, rng: random.Random, software: bool):
        self.r = rng
        self.software = software
        self.procs = [f"p{i}" for i in range(rng.randint(0, 3))]
        self.left = rng.randint(10, 40)

    def expr(self, depth: int = 0) -> str:
        r = self.r.random()
        if depth > 2 or r < 0.35:
            return self.r.choice(_READ) if self.r.random() < 0.6 else self.r.choice(_CONSTS)
        if r < 0.75:
            return f"({self.expr(depth + 1)} {self.r.choice(_OPS)} {self.expr(depth + 1)})"
        if r < 0.85:
            return f"{self.r.choice(['-', '!', '~'])}({self.expr(depth + 1)})"
        if r < 0.93:
            return f"gvarget({self.r.choice(['1000', '1001', '7180', '0x403', '6060', '5021', '20000'])})"
        return f"portget({self.r.choice(['3', '4', '6', '9'])})"

    def cond(self) -> str:
        return self.expr(1)

    def block(self, depth: int) -> str:
        return " ".join(self.stmt(depth) for _ in range(self.r.randint(1, 3)))

    def stmt(self, depth: int) -> str:
        self.left -= 1
        r = self.r.random()
        v = self.r.choice(_VARS)
        if self.left <= 0 or depth > 3:
            return f"{v} = {self.expr()};"
        if r < 0.25:
            return f"{v} = {self.expr()};"
        if r < 0.32:
            return f"{v}{self.r.choice(['++', '--'])};"
        if r < 0.45:
            s = f"if ({self.cond()}) {{ {self.block(depth + 1)} }}"
            if self.r.random() < 0.5:
                s += f" else {{ {self.block(depth + 1)} }}"
            return s + ";"
        if r < 0.55:
            n = self.r.randint(1, 5)
            return f"{v} = {n}; do {{ {self.block(depth + 1)} {v}--; }} while ({v} > 0);"
        if r < 0.6:
            n = self.r.randint(0, 4)
            return f"{v} = {n}; while ({v} > 0) {{ {self.block(depth + 1)} {v}--; }};"
        if r < 0.66:
            return f"portset({self.r.choice(['2', '3', '4', v])}); portclear({self.r.choice(['1', '2'])});"
        if r < 0.74:
            addr = self.r.choice(["20000", "20001", "1000", "7278", "7270", "8634", "8635",
                                  "100041", "100040", "100020", f"20000 + ({v} & 3)"])
            return f"gvarset({addr}, {self.expr()});"
        if r < 0.77:
            return f"g0moveA({self.r.choice(['0', '1', '3', '0x81'])}, {self.r.choice(['1', '4'])}, {self.expr()});"
        if r < 0.82:
            code = self.r.choice(["PLCCMD_REPLY_TO_MYCNC", "PLCCMD_LINE_STOP", "146", "0-5"])
            return f"command = {self.expr()}; message = {code};"
        if r < 0.9 and self.procs:
            return f"{self.r.choice(self.procs)}();"
        if r < 0.93:
            return f"if ({self.cond()}) {{ exit({self.expr()}); }};"
        return f"proc = {self.expr()};"

    def source(self) -> str:
        parts = []
        for p in self.procs:
            self.left = self.r.randint(3, 12)
            parts.append(f"{p}()\n{{\n  {self.block(1)}\n}};")
        self.left = self.r.randint(10, 40)
        body = self.block(0)
        body += " " + " ".join(f"{p}();" for p in self.procs if self.r.random() < 0.7)
        tail = self.r.choice(["exit(99);", "exit(vexit);", ""])
        parts.append(f"main()\n{{\n  {body}\n  {tail}\n}};")
        return "\n".join(parts) + "\n"


def random_source(rng: random.Random, software: bool = False) -> str:
    return _Src(rng, software).source()
