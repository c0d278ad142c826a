# Scheduling hints for ctest -j on a fresh build (no Testing/ cost history):
# the longest tests start first, so the one long test does not begin after
# half the suite and finish alone. The costs are the seconds each took in
# a clean-clone run of .ci/run on the 2-core machine (2026-12-02); only the order
# matters. Included after the tests discover_tests.cmake found. ctest
# ignores a name that matches no test: keep these in step with the names.
# (Tests added in CMakeLists.txt itself are defined after this file runs:
# they get their COST there.)
foreach(entry
    "CLI: reproduce --quick writes every artefact with its verdicts, keeps finished trainings on SIGTERM and resumes=330"
    "CLI: train --quick learns, is deterministic, and its model runs in the loop=300"
    "The default model: three modalities beat each single one on held-out trajectories=115"
    "CLI: train --jobs 2 and mpirun simulate the episodes one job does, byte for byte, and extend a saved set exactly=150"
    "Kill: training killed at random moments leaves no half-written model or data=90"
    "CLI: train --variant trains a variant on shared encoders that runs in the loop under its name and on modality subsets=60"
    "CLI: dataset writes every field of the training episodes to HDF5, the same bytes whatever --jobs or mpirun, with the node encoders' latents given a model=60"
    "Kill: a dataset export killed at random moments leaves no half-written file=40"
    "CLI: the Python example trains on uavsim dataset's HDF5 and its model runs in the loop, in metrics, estimates, beams and a sweep=40")
  string(FIND "${entry}" "=" at REVERSE)
  string(SUBSTRING "${entry}" 0 ${at} name)
  math(EXPR from "${at} + 1")
  string(SUBSTRING "${entry}" ${from} -1 cost)
  set_tests_properties("${name}" PROPERTIES COST ${cost})
endforeach()
