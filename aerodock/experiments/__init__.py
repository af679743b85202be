"""The paper's experiments: ``reproduce`` (simulation), ``real_data`` (Neural-Swarm), report."""
