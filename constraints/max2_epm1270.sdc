# finestep's CPLD configuration on the MAX II EPM1270: 50 MHz.
create_clock -name clk50 -period 20.000 [get_ports {clk50}]
derive_clock_uncertainty
# Every input is asynchronous and passes a two-flop synchroniser in the core; every
# output is a flip-flop (bus_ad's enable too) with no timing relation to the host's clock.
set_false_path -from [get_ports {reset_n bus_* estop_pin probe_pin mpg_* enc_*}]
set_false_path -to [get_ports {bus_ad[*] irq pin_*}]
