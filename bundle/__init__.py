"""`doctrpp bundle`: model files + a machine-readable contract + platform notes for apps."""
