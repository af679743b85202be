"""The mission's decisions, one module each: the leader, the approach (plan and re-plan), the
terminal hold, the aborts, the gate's outcome, the back-off, the active trigger."""
