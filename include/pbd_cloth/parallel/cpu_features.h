// What the processor offers, asked once (the answer does not change while the program runs): the
// one place the kernels' run-time dispatch (*_kernels.cpp) asks. False wherever the program was
// not built for x86-64 with GCC's target attributes (no AVX paths there).
#pragma once

namespace pbd_cloth {

bool cpuHasAvx2();
bool cpuHasAvx512F();   // AVX-512 Foundation (every AVX-512 processor)
bool cpuHasAvx512Vl();  // AVX-512F and VL (512-bit instructions on 256-bit registers)

}  // namespace pbd_cloth
