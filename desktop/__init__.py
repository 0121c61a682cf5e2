"""The desktop tools: `python -m desktop COMMAND` (= `python -m host_sim COMMAND`); each command
module has main(argv) -> exit code. They drive the simulator (host_sim/) and the firmware."""
