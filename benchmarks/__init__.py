"""FPS and accuracy-drop benchmarks, and the paper's metrics (`doctrpp.benchmarks.metrics`)."""
