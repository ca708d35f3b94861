# Lattice Diamond project for finestep on the XP2 LFXP2-5E-6TN144C. `make diamond`
# copies this script to build/diamond/xp2_brevia2/build.tcl with the source list and the
# register map's include path filled in; run it there with Diamond's Tcl shell:
#   diamondc build.tcl
prj_project new -name finestep_xp2 -impl impl1 -dev LFXP2-5E-6TN144C -synthesis "lse" -lpf xp2_brevia2.lpf
prj_impl option top xp2_brevia2
prj_impl option {include path} {@INCLUDE@}
foreach source {@SOURCES@} {
    prj_src add $source
}
prj_project save
prj_run Synthesis -impl impl1
prj_run Translate -impl impl1
prj_run Map -impl impl1
prj_run PAR -impl impl1
prj_run PAR -impl impl1 -task PARTrace
prj_run Export -impl impl1 -task Bitgen
prj_project close
