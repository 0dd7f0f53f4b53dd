"""``python -m ftlbo_mav ...`` is ``ftlbo-mav ...``."""

from .cli import main

if __name__ == "__main__":
    main()
