"""Host link: SPI and UART transports, the command decoder and the register file."""
