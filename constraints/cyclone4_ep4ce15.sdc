# finestep on the Cyclone IV E EP4CE15F23C8: 50 MHz in, 100 MHz from the PLL.
create_clock -name clk50 -period 20.000 [get_ports {clk50}]
derive_pll_clocks
derive_clock_uncertainty
# Every input is asynchronous and passes a two-flop synchroniser in the core; every
# output is a flip-flop with no timing relation to another device's clock.
set_false_path -from [get_ports {reset_n spi_* estop_pin probe_pin mpg_* enc_*}]
set_false_path -to [get_ports {led_n spi_miso irq pin_*}]
