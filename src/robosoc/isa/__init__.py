"""The RV32I (+ M multiply) instruction set as data: encodings, decoding, disassembly."""
