"""What the hub counts for its operators (Prometheus)."""
