"""Random vibration: stationary response to a one-sided input PSD by the exact modal integral
(:mod:`.response`), the input PSD table (:mod:`.psd_input`), and log–log figures (:mod:`.figures`)."""
