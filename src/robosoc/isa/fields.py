"""Bit fields of RV32 instruction words (plain Python; the numba decoder has its own copy in kernels)."""


def sext(value: int, bits: int) -> int:
    """Sign-extend the low ``bits`` of ``value``."""
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >> (bits - 1) else value


def rd(w: int) -> int:
    return (w >> 7) & 31


def rs1(w: int) -> int:
    return (w >> 15) & 31


def rs2(w: int) -> int:
    return (w >> 20) & 31


def imm_i(w: int) -> int:
    return sext(w >> 20, 12)


def imm_s(w: int) -> int:
    return sext(((w >> 25) << 5) | ((w >> 7) & 31), 12)


def imm_b(w: int) -> int:
    v = ((w >> 31) << 12) | (((w >> 7) & 1) << 11) | (((w >> 25) & 0x3F) << 5) | (((w >> 8) & 0xF) << 1)
    return sext(v, 13)


def imm_u(w: int) -> int:
    return sext(w & 0xFFFFF000, 32)


def imm_j(w: int) -> int:
    v = ((w >> 31) << 20) | (((w >> 12) & 0xFF) << 12) | (((w >> 20) & 1) << 11) | (((w >> 21) & 0x3FF) << 1)
    return sext(v, 21)
