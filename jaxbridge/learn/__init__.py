"""Learning the bridge: Q-network, double DQN, replay buffer, transitions, optimiser, the six approaches, the
resolved setup of a run, seeds over devices and the jitted online cycle."""
