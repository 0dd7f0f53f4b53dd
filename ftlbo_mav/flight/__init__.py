"""Flying a planned formation: pre-flight, synchronized start, monitoring, reports."""
