// Trivial harness for the cocotb encoder model self-test (tb/tests/cocotb_encoder_checks.py).
// Python plays an ideal master on `ma` and the encoder model drives `slo`; both are
// top-level inputs, so cocotb can drive them. No logic: the model is checked on its own.
`timescale 1ns / 1ps
module ma_loopback (
    input wire ma,
    input wire slo
);
endmodule
