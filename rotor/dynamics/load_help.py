"""The grammar of a load on the command line (``--load``), in a module of its own so
that ``rotor steady --help`` shows it without importing JAX."""

__all__ = ["LOAD_HELP"]

LOAD_HELP = (
    "a load is one of: none; constant:TORQUE_NM (or just TORQUE_NM); poly:A,B,C (A + B·ω + C·ω², ω in rad/s); "
    "propeller:TORQUE_NM,RPM; table:RPM=TORQUE_NM,RPM=TORQUE_NM,...; "
    "step:TORQUE_BEFORE,TORQUE_AFTER,TIME_S[,RAMP_S]"
)
