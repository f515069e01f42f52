"""Programs for the chip: ELF images (segments, symbols) and the debug information read from them."""
