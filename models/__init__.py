"""Registry of learned-dynamics models assembled from inductive biases."""
