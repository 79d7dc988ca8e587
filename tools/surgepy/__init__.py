"""The Python modules that surge's tools, tests and studies share: vtp (numpy reader and writer for the .vtp/.pvd
files surge writes), client (the live stream and control socket, docs/protocol.md), run_params (a run folder's
params.ini), cli_checks (option checks and the one-line error, exit status 2) and study (resumable runs and the
CSV tables of the study drivers). A script in tools/ imports them as `from surgepy import vtp`; a study or a script
in bench/ first puts tools/ on sys.path; the tests run with PYTHONPATH=tools (tests/CMakeLists.txt). Importing the
package loads no module: each is imported by name, so a tool that needs no pyzmq does not need it installed."""
