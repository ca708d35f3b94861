// FINESTEP_MUTSEL for sim/mutants_rtl/finestep_mutsel.v: the mutant the RTL mutation build
// runs (scripts/mutants_rtl.py); unset or 0 is the unmutated design.
#include <cstdlib>

extern "C" int finestep_mutsel_env() {
    const char *value = std::getenv("FINESTEP_MUTSEL");
    return value ? std::atoi(value) : 0;
}
